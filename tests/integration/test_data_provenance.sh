#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tests/data holds unmodified copies of shared data (tests/data/README.md): every file there is
# listed with its source, licence and checksum, still has that checksum, and has the same bytes as
# its original in ../shared/data (the one test that reads ../shared/data, under the README's
# skip-or-fail rule).
source "$(dirname "$0")/lib.sh"
readme="$source_dir/tests/data/README.md"
names=()
# Rows of the README's table: | `file` | what | source | licence | sha256 |
while IFS='|' read -r _ name _ _ _ sum _; do
  name="$(echo "$name" | tr -d ' `')"
  sum="$(echo "$sum" | tr -d ' `')"
  [[ "$sum" =~ ^[0-9a-f]{64}$ ]] || continue
  names+=("$name")
  if [ "$(sha256sum "$source_dir/tests/data/$name" 2>/dev/null | cut -d' ' -f1)" = "$sum" ]; then
    pass "$name has the checksum tests/data/README.md records"
  else
    fail "tests/data/$name is missing or differs from the checksum in tests/data/README.md"
  fi
done <"$readme"
[ ${#names[@]} -gt 0 ] || fail "no file with a checksum in $readme"
for file in "$source_dir"/tests/data/*; do
  name="$(basename "$file")"
  [ "$name" = README.md ] && continue
  grep -qF "| \`$name\` |" "$readme" && pass "$name is listed" || fail "tests/data/$name is not listed in $readme"
done
for name in "${names[@]}"; do
  original="$source_dir/../shared/data/$name"
  require_shared_data "$original"
  cmp -s "$source_dir/tests/data/$name" "$original" && pass "$name is byte for byte its original" ||
    fail "tests/data/$name differs from $original"
done
finish
