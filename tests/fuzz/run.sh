#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs each libFuzzer target in BUILD_DIR for SECONDS (ctest fuzz.messages; docs/hostile_input.md,
# "Fuzzing"). The main build builds them (tests/CMakeLists.txt); if BUILD_DIR holds none yet, this
# configures and builds them with clang first. Exit 0: no finding; 1: a finding or a build failure (the crashing
# input is kept in BUILD_DIR/findings); 77: no clang with libFuzzer on this machine (skipped).
# Usage: run.sh BUILD_DIR SECONDS
set -uo pipefail
build_dir="$1"
seconds="$2"
source_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
clangxx="$(command -v clang++ || true)"
if [ -z "$clangxx" ] || ! echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' |
  "$clangxx" -x c++ -fsanitize=fuzzer - -o /dev/null 2>/dev/null; then
  echo "SKIP: clang++ with libFuzzer not found (Debian package clang; deploy/install-deps.sh)"
  exit 77
fi
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
start=$(date +%s)
if [ ! -f "$build_dir/build.ninja" ]; then
  cmake -S "$source_dir" -B "$build_dir" -G Ninja -DCMAKE_CXX_COMPILER="$clangxx" -DCMAKE_BUILD_TYPE=None \
    "${launcher[@]}" >"$build_dir.configure.log" 2>&1 || { cat "$build_dir.configure.log"; exit 1; }
fi
cmake --build "$build_dir" -j "$(nproc)" || exit 1
echo "fuzz targets built in $(( $(date +%s) - start )) s"
mkdir -p "$build_dir/corpus" "$build_dir/findings"
status=0
for target in fuzz_messages; do
  # Fixed seed: the same inputs on every run. -rss_limit_mb bounds a decoder's allocation.
  "$build_dir/$target" -seed=20 -max_total_time="$seconds" -rss_limit_mb=2048 -max_len=65536 \
    -artifact_prefix="$build_dir/findings/$target-" "$build_dir/corpus" 2>&1 | tail -15
  rc=${PIPESTATUS[0]}
  if [ "$rc" -eq 0 ]; then echo "PASS: $target ran ${seconds} s without a finding"; else echo "FAIL: $target exit $rc"; status=1; fi
done
exit $status
