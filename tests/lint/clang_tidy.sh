#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Lint test: clang-tidy with the project's rules (.clang-tidy; tests/.clang-tidy relaxes a few for
# tests) over the project translation units of <build dir>/compile_commands.json, two at a time.
# Headers are checked through the sources that include them (HeaderFilterRegex). Fails on any
# warning or error and lists them; generated DDS code in the build tree is not ours and is skipped.
#
# By default only what may have changed is linted (docs/testing.md, "Lint"; tests/lint/tidy_select.py):
# the units changed since the commit recorded as lint-clean in tests/lint/clang_tidy.clean, or
# including a project file changed since (uncommitted changes count), all of them when a
# .clang-tidy changed; less those this build directory has already linted clean with the same
# content, includes, rules and flags (<build dir>/lint/clang_tidy.cache).
usage() {
  cat <<'EOF'
Usage: tests/lint/clang_tidy.sh [--full] [--record] <build dir> <source dir> [file regex]
  --full    lint every project translation unit (ignores the lint-clean record and the cache):
            the full lint, e.g. `bash tests/lint/clang_tidy.sh --full build .`
            (or PANOPTES_LINT_FULL=1 ctest -R lint.clang_tidy)
  --record  after a clean run on a tree without uncommitted changes, write HEAD into
            tests/lint/clang_tidy.clean (commit that file: later runs lint from there)
  PANOPTES_LINT_JOBS  parallel clang-tidy runs (default 2)
EOF
}
set -uo pipefail
full="${PANOPTES_LINT_FULL:-}"
record=""
while [ $# -gt 0 ]; do
  case "$1" in
    --full) full=1; shift ;;
    --record) record=1; shift ;;
    -h | --help) usage; exit 0 ;;
    *) break ;;
  esac
done
[ $# -ge 2 ] || { usage >&2; exit 2; }
build_dir="$(cd "$1" && pwd)"
source_dir="$(cd "$2" && pwd)"
only="${3:-.}"
jobs="${PANOPTES_LINT_JOBS:-2}"
tidy="$(command -v clang-tidy || command -v clang-tidy-14 || true)"
[ -n "$tidy" ] || { echo "FAIL: clang-tidy is not installed (deploy/install-deps.sh installs it)"; exit 1; }
[ -f "$build_dir/compile_commands.json" ] || { echo "FAIL: $build_dir/compile_commands.json is missing"; exit 1; }
version="$("$tidy" --version | sed -n 's/.*version \([0-9.]*\).*/\1/p')"

logs="$(mktemp -d)"
trap 'rm -rf "$logs"' EXIT
python3 "$source_dir/tests/lint/tidy_select.py" select --build "$build_dir" --source "$source_dir" --only "$only" \
  --tidy-version "$version" ${full:+--full} >"$logs/selected" || { echo "FAIL: tests/lint/tidy_select.py"; exit 1; }
cut -f1 "$logs/selected" >"$logs/files"
# The unit tests' compile commands include a precompiled header GCC made (tests/CMakeLists.txt),
# which clang cannot read: clang-tidy gets the commands without it (the test files include what
# they use themselves).
mkdir -p "$logs/db"
python3 - "$build_dir/compile_commands.json" "$logs/db/compile_commands.json" <<'PY' || { echo "FAIL: filtering compile_commands.json"; exit 1; }
import json, re, sys
commands = json.load(open(sys.argv[1], encoding="utf-8"))
for entry in commands:
    entry["command"] = re.sub(r" -Winvalid-pch| -include \S*cmake_pch\.hxx", "", entry["command"])
json.dump(commands, open(sys.argv[2], "w", encoding="utf-8"))
PY
start=$(date +%s)
# One log per file, so that the parallel runs' lines cannot interleave; a run that fails without a
# diagnostic (a crash) becomes one.
xargs -a "$logs/files" -d '\n' -r -P "$jobs" -I '{}' sh -c \
  'log="$3/$(echo "$4" | tr / _).log"; "$1" -p "$2" --quiet "$4" >"$log" 2>&1 ||
     echo "$4:1:1: error: clang-tidy exited with $?" >>"$log"' sh "$tidy" "$logs/db" "$logs" '{}'
seconds=$(($(date +%s) - start))
echo "clang-tidy $version: $(wc -l <"$logs/files") files linted, $jobs jobs, ${seconds} s"
# The units linted clean go into this build directory's cache.
: >"$logs/clean_keys"
while IFS=$'\t' read -r file key; do
  log="$logs/$(echo "$file" | tr / _).log"
  [ -n "$key" ] && ! grep -qE '^/.*:[0-9]+:[0-9]+: (warning|error):' "$log" 2>/dev/null && echo "$key" >>"$logs/clean_keys"
done <"$logs/selected"
python3 "$source_dir/tests/lint/tidy_select.py" record --build "$build_dir" --source "$source_dir" --keys "$logs/clean_keys"
# Each finding once: a header's is reported by every source that includes it.
cat "$logs"/*.log 2>/dev/null | grep -E '^/.*:[0-9]+:[0-9]+: (warning|error):' | sed "s#^$source_dir/##" |
  sort -u >"$logs/findings"
if [ -s "$logs/findings" ]; then
  cat "$logs/findings"
  echo "FAIL: $(wc -l <"$logs/findings") clang-tidy finding(s) (rules: .clang-tidy)"
  exit 1
fi
echo "PASS: no clang-tidy findings"
if [ -n "$record" ]; then
  if [ "$only" != "." ] || [ -n "$(git -C "$source_dir" status --porcelain --untracked-files=normal)" ]; then
    echo "not recorded: the run must cover every file of a tree without uncommitted changes" >&2
    exit 1
  fi
  head="$(git -C "$source_dir" rev-parse HEAD)"
  stamp="$source_dir/tests/lint/clang_tidy.clean"
  [ -f "$stamp" ] && sed -i "/^[0-9a-f]\{40\}$/d" "$stamp"
  echo "$head" >>"$stamp"
  echo "recorded $head as lint-clean in tests/lint/clang_tidy.clean: commit it"
fi
