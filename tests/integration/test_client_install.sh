#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The installed client library (issue 15, docs/clients.md): `cmake --install` into a prefix gives
# libpanoptes_client.so (exporting only panoptes::client), its header (plain C++17, no DDS), a CMake
# package and a pkg-config file. examples/sample_client.cpp is built as an outside project with
# find_package(Panoptes) and with pkg-config, and both builds run: they find the installed loopback
# profile by themselves, report an empty domain, and print frames from a publisher.
source "$(dirname "$0")/lib.sh"
prefix="$work/prefix"

expect_exit 0 "cmake --install into a prefix" -- cmake --install "$build_dir" --prefix "$prefix"
soname=$(objdump -p "$build_dir"/lib/libpanoptes_client.so | sed -n 's/.*SONAME *//p')
for path in "lib/$soname" lib/libpanoptes_client.so include/panoptes/client/client.h \
  lib/cmake/Panoptes/PanoptesConfig.cmake lib/cmake/Panoptes/PanoptesConfigVersion.cmake \
  lib/cmake/Panoptes/PanoptesTargets.cmake lib/pkgconfig/panoptes-client.pc share/panoptes/dds/loopback.xml; do
  [ -e "$prefix/$path" ] && pass "installed $path" || fail "$path is not installed"
done
others=$(nm -D --defined-only "$prefix/lib/libpanoptes_client.so" | c++filt | awk '{$1=$2=""; print}' |
  grep -v "panoptes::client::" | grep -c . || true)
[ "$others" -eq 0 ] && pass "the library exports panoptes::client only" ||
  { fail "it exports $others other symbols"; nm -D --defined-only "$prefix/lib/libpanoptes_client.so" | c++filt | grep -v "panoptes::client::" | head; }
printf '#include <panoptes/client/client.h>\nint main() { return 0; }\n' >"$work/header_only.cpp"
expect_exit 0 "the public header compiles as C++17 with no include path but its own" -- \
  g++ -std=c++17 -fsyntax-only -Wall -Wextra -Wpedantic -Werror -I"$prefix/include" "$work/header_only.cpp"

# --- an outside project: find_package(Panoptes) ---------------------------------------------------
mkdir -p "$work/app"
cp "$source_dir/examples/sample_client.cpp" "$work/app/"
cat >"$work/app/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.16)
project(panoptes_app CXX)
find_package(Panoptes 0.1 REQUIRED)
add_executable(sample_client sample_client.cpp)
target_link_libraries(sample_client PRIVATE Panoptes::client)
CMAKE
expect_exit 0 "configure with find_package(Panoptes)" -- cmake -S "$work/app" -B "$work/app/build" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release
expect_exit 0 "build it" -- cmake --build "$work/app/build"
# --- and with pkg-config ---------------------------------------------------------------------------
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
expect_exit 0 "pkg-config knows panoptes-client" -- pkg-config --exists --print-errors panoptes-client
# shellcheck disable=SC2046
expect_exit 0 "build with pkg-config" -- g++ -std=c++17 -O2 "$work/app/sample_client.cpp" -o "$work/app/sample_pc" \
  $(pkg-config --cflags --libs panoptes-client)

# --- run them: no profile given, they use the installed one -----------------------------------------
unset PANOPTES_DDS_PROFILE
expect_exit 1 "the find_package build reports an empty domain" -- "$work/app/build/sample_client" \
  --domain "$empty_domain" --timeout-s 1
expect_stderr_matches "no data for [0-9]+\\.[0-9] s" "it says 'no data for N s'"
expect_stderr_contains "DDS profile $prefix/share/panoptes/dds/loopback.xml" "it found the installed loopback profile"
expect_exit 1 "the pkg-config build (LD_LIBRARY_PATH) reports an empty domain" -- env LD_LIBRARY_PATH="$prefix/lib" \
  "$work/app/sample_pc" --domain "$empty_domain" --timeout-s 1
expect_stderr_contains "DDS profile $prefix/share/panoptes/dds/loopback.xml" "it found the installed loopback profile"

[ -x "$bin/bench_client" ] || { echo "SKIP: the live part needs bench_client (PANOPTES_BUILD_BENCHMARKS)"; [ "$failures" -eq 0 ] && exit 77; finish; }
"$work/app/build/sample_client" --frames 100 --timeout-s 15 >"$work/cmake_app.out" 2>"$work/cmake_app.err" &
cmake_app=$!
LD_LIBRARY_PATH="$prefix/lib" "$work/app/sample_pc" --frames 100 --timeout-s 15 >"$work/pc_app.out" 2>"$work/pc_app.err" &
pc_app=$!
pids+=("$cmake_app" "$pc_app")
expect_exit 0 "a publisher of frames (bench_client --publish) served both" -- "$bin/bench_client" --publish --rate 200 \
  --duration 2 --readers 2 --domain "$PANOPTES_DOMAIN"
for app in cmake_app pc_app; do
  wait "${!app}"
  rc=$?
  [ "$rc" -eq 0 ] && grep -q "^frame 100 " "$work/$app.out" && grep -q "body 2 tool .*tracked" "$work/$app.out" &&
    grep -q "marker .* unlabelled" "$work/$app.out" && pass "$app printed 100 frames with bodies and markers" ||
    { fail "$app: exit $rc"; tail -3 "$work/$app.err"; tail -3 "$work/$app.out"; }
done
finish
