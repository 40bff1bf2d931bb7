#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Lint test: every project .cpp/.h is formatted as the project's .clang-format says
# (clang-format --dry-run --Werror). Build trees (any folder holding a CMakeCache.txt, or named
# build*), npm's node_modules and hidden folders are not ours and are skipped (pruned before the
# CMakeCache.txt probe, which otherwise runs once per npm folder). To fix: clang-format -i <file>.
# Usage: clang_format.sh <source dir>
set -uo pipefail
source_dir="$(cd "$1" && pwd)"
format="$(command -v clang-format || command -v clang-format-14 || true)"
[ -n "$format" ] || { echo "FAIL: clang-format is not installed (deploy/install-deps.sh installs it)"; exit 1; }

mapfile -t files < <(cd "$source_dir" && find . \( -name '.*' -o -name 'build*' -o -name node_modules -o -exec test -e '{}/CMakeCache.txt' \; \) \
  -mindepth 1 -type d -prune -o -type f \( -name '*.cpp' -o -name '*.h' \) -print | sed 's#^\./##' | sort)
[ ${#files[@]} -gt 0 ] || { echo "FAIL: no .cpp/.h files under $source_dir"; exit 1; }

# Forty files per clang-format on every core (one process per file cost 12 s of the suite's
# time, batches 3 s); the files that differ are read from the diagnostics, which name them.
mapfile -t unformatted < <(printf '%s\0' "${files[@]}" | (cd "$source_dir" && xargs -0 -P "$(nproc)" -n 40 \
  "$format" --dry-run --Werror --style=file 2>&1 >/dev/null) |
  sed -n 's/^\(.*\):[0-9]*:[0-9]*: error: code should be clang-formatted.*/\1/p' | sort -u)
echo "clang-format $("$format" --version | sed -n 's/.*version \([0-9.]*\).*/\1/p'): ${#files[@]} files"
if [ ${#unformatted[@]} -ne 0 ]; then
  printf '  not formatted: %s\n' "${unformatted[@]}"
  echo "FAIL: ${#unformatted[@]} file(s) differ from .clang-format (fix: clang-format -i <file>)"
  exit 1
fi
echo "PASS: every file is formatted"
