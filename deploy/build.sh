#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs missing dependencies (Debian 12) and builds Panoptes into build/ (programs in build/bin/).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

if ! command -v fastddsgen >/dev/null 2>&1 || ! dpkg-query -W -f='${Status}' libceres-dev 2>/dev/null | grep -q "ok installed"; then
  bash deploy/install-deps.sh
else
  bash deploy/install-deps.sh >/dev/null
fi

build_dir="${PANOPTES_BUILD_DIR:-build}"
if [ ! -f "$build_dir/build.ninja" ]; then
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${PANOPTES_BUILD_TYPE:-Release}" ${PANOPTES_CMAKE_ARGS:-}
fi
cmake --build "$build_dir" -j "$(nproc)"
