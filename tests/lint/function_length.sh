#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Lint test: no C++ function outside the tests is longer than 100 lines (the project's style, issue
# 31), counted by universal-ctags from a function's first line to its closing brace. Every
# top-level source folder is scanned (camera_node, common, estimator_node, examples, tools, ...),
# except tests/, build trees (build*, any folder holding a CMakeCache.txt), hidden folders and
# node_modules. A failure names file:function:lines; split the function into named steps.
# Usage: function_length.sh <source dir> [max lines, default 100]
set -uo pipefail
source_dir="$(cd "$1" && pwd)"
max_lines="${2:-100}"
ctags_bin="$(command -v ctags || true)"
if [ -z "$ctags_bin" ] || ! "$ctags_bin" --version 2>/dev/null | grep -q "Universal Ctags"; then
  echo "FAIL: universal-ctags is not installed (deploy/install-deps.sh installs it)"
  exit 1
fi

# <end line> <start line> <function> <file> for every C++ function definition under the arguments.
function_extents() {
  "$ctags_bin" -R --languages=C++ --kinds-C++=f --fields=+ne --exclude=node_modules -x \
    --_xformat="%{end} %{line} %N %F" "$@"
}

# ctags reports no end line for a definition it cannot parse to its closing brace; a ctags that
# never does would pass every tree, so first check that it measures a known function.
probe_dir="$(mktemp -d)"
trap 'rm -rf "$probe_dir"' EXIT
{
  echo "int probe_function() {"
  for ((i = 0; i < max_lines; ++i)); do echo "  int v$i = $i;"; done
  echo "  return 0;"
  echo "}"
} >"$probe_dir/probe.cpp"
probe="$(cd "$probe_dir" && function_extents probe.cpp | awk '{print $1 - $2 + 1, $3}')"
if [ "$probe" != "$((max_lines + 3)) probe_function" ]; then
  echo "FAIL: ctags did not measure a $((max_lines + 3))-line probe function (got '$probe')"
  exit 1
fi

mapfile -t folders < <(cd "$source_dir" && find . -mindepth 1 -maxdepth 1 -type d \
  ! -name '.*' ! -name 'build*' ! -name tests ! -exec test -e '{}/CMakeCache.txt' \; -print | sed 's#^\./##' | sort)
[ ${#folders[@]} -gt 0 ] || { echo "FAIL: no source folders under $source_dir"; exit 1; }

extents="$(cd "$source_dir" && function_extents "${folders[@]}")"
measured=$(printf '%s\n' "$extents" | grep -c . || true)
[ "$measured" -gt 0 ] || { echo "FAIL: ctags found no C++ functions in ${folders[*]}"; exit 1; }
too_long="$(printf '%s\n' "$extents" |
  awk -v max="$max_lines" 'NF >= 4 { n = $1 - $2 + 1; if (n > max) print $4 ":" $3 ":" n }' | sort)"

echo "function length: $measured functions in ${folders[*]}, at most $max_lines lines each"
if [ -n "$too_long" ]; then
  printf '  too long (file:function:lines): %s\n' $too_long
  echo "FAIL: $(printf '%s\n' "$too_long" | wc -l) function(s) over $max_lines lines; split them into named steps"
  exit 1
fi
echo "PASS: no function is over $max_lines lines"
