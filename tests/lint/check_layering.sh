#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The `lint.layering` test: check_layering.sh <build dir>
# Fails, naming the library, the dependency or file:line, and the rule, when a guarded library
# links or includes what the layering forbids. The rules and their reasons are in
# cmake/PanoptesLayering.cmake, which writes the manifests read here at configure time.
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: check_layering.sh <build dir>" >&2; exit 2; }
dir="$1/layering"
[ -f "$dir/rules.txt" ] || { echo "layering: no $dir/rules.txt (configure first)"; exit 1; }
violations=0
checked=0
while IFS= read -r rule; do
  [ -n "$rule" ] || continue
  target="${rule%%|*}"
  why="${rule##*|}"
  middle="${rule#*|}"
  middle="${middle%|*}"
  if [[ "$middle" == *"|#include"* ]]; then
    link_regex="${middle%%|#include*}"
    source_regex="#include${middle#*|#include}"
  else
    link_regex="${middle%|}"
    source_regex=""
  fi
  manifest="$dir/$target.txt"
  [ -f "$manifest" ] || continue
  checked=$((checked + 1))
  while IFS= read -r link; do
    name="${link#link }"
    if [[ "$name" =~ ^(.*::)?($link_regex)(::.*)?$ ]]; then
      echo "layering: $target links $name: forbidden ($why)"
      violations=$((violations + 1))
    fi
  done < <(grep '^link ' "$manifest" || true)
  if [ -n "$source_regex" ]; then
    while IFS= read -r file; do
      path="${file#file }"
      while IFS= read -r hit; do
        echo "layering: $path:$hit (in $target): forbidden ($why)"
        violations=$((violations + 1))
      done < <(grep -nE "$source_regex" "$path" | grep -vE '^[0-9]+: *//' || true)
    done < <(grep '^file ' "$manifest" || true)
  fi
done < "$dir/rules.txt"
if [ "$checked" -eq 0 ]; then
  echo "layering: no manifests in $dir"
  exit 1
fi
if [ "$violations" -gt 0 ]; then
  echo "layering: $violations violation(s) in $checked libraries"
  exit 1
fi
echo "layering: $checked libraries checked, no violations"
