#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Lint test: clang-tidy with the project's rules (.clang-tidy; tests/.clang-tidy relaxes a few for
# tests) over every project translation unit in <build dir>/compile_commands.json, two at a time.
# Headers are checked through the sources that include them (HeaderFilterRegex). Fails on any
# warning or error and lists them; generated DDS code in the build tree is not ours and is skipped.
# Usage: clang_tidy.sh <build dir> <source dir> [file regex]
set -uo pipefail
build_dir="$(cd "$1" && pwd)"
source_dir="$(cd "$2" && pwd)"
only="${3:-.}"
jobs="${PANOPTES_LINT_JOBS:-2}"
tidy="$(command -v clang-tidy || command -v clang-tidy-14 || true)"
[ -n "$tidy" ] || { echo "FAIL: clang-tidy is not installed (deploy/install-deps.sh installs it)"; exit 1; }
[ -f "$build_dir/compile_commands.json" ] || { echo "FAIL: $build_dir/compile_commands.json is missing"; exit 1; }

# CMake writes one absolute `"file": "<path>"` line per entry.
mapfile -t files < <(sed -n 's/^ *"file": "\(.*\)",\{0,1\}$/\1/p' "$build_dir/compile_commands.json" |
  grep "^$source_dir/" | grep -v "^$build_dir/" | grep -E -- "$only" | sort -u)
[ ${#files[@]} -gt 0 ] || { echo "FAIL: no project sources in $build_dir/compile_commands.json"; exit 1; }

logs="$(mktemp -d)"
trap 'rm -rf "$logs"' EXIT
start=$(date +%s)
# One log per file, so that the parallel runs' lines cannot interleave; a run that fails without a
# diagnostic (a crash) becomes one.
printf '%s\n' "${files[@]}" | xargs -P "$jobs" -I '{}' sh -c \
  'log="$3/$(echo "$4" | tr / _).log"; "$1" -p "$2" --quiet "$4" >"$log" 2>&1 ||
     echo "$4:1:1: error: clang-tidy exited with $?" >>"$log"' sh "$tidy" "$build_dir" "$logs" '{}'
seconds=$(($(date +%s) - start))
echo "clang-tidy $("$tidy" --version | sed -n 's/.*version \([0-9.]*\).*/\1/p'): ${#files[@]} files, $jobs jobs, ${seconds} s"
# Each finding once: a header's is reported by every source that includes it.
cat "$logs"/*.log | grep -E '^/.*:[0-9]+:[0-9]+: (warning|error):' | sed "s#^$source_dir/##" | sort -u >"$logs/findings"
if [ -s "$logs/findings" ]; then
  cat "$logs/findings"
  echo "FAIL: $(wc -l <"$logs/findings") clang-tidy finding(s) (rules: .clang-tidy)"
  exit 1
fi
echo "PASS: no clang-tidy findings"
