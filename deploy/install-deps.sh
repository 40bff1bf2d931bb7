#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs every Debian 12 package Panoptes needs to build, test and run the demo.
# Idempotent and non-interactive: packages already present are not touched.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

packages=(
  build-essential cmake ninja-build pkg-config ccache git
  libfastrtps-dev fastddsgen fastdds-tools
  libopencv-dev libeigen3-dev libceres-dev
  libpng-dev libjpeg-dev  # picture files (common/io image_file), not OpenCV's imgcodecs
  opencv-doc
  libaravis-dev aravis-tools libusb-1.0-0-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format clang-tidy python3-yaml
  universal-ctags  # lint.function_length (tests/lint/function_length.sh)
  clang  # libFuzzer targets (tests/fuzz, docs/hostile_input.md)
  cyclonedds-dev cyclonedds-tools pybind11-dev python3-dev python3-numpy python3-matplotlib
  iproute2 procps nftables tcpdump openssl libtinyxml2-dev
  libzstd-dev liblz4-dev libboost-dev chromium
)
# Node.js and npm run the browser tests and the independent file-format checks. A machine that
# already has them (from any source) keeps its own; otherwise Debian's are installed.
if ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# npm packages: every folder with a committed package-lock.json gets exactly its locked versions
# (npm ci) from the npm registry. Nothing is downloaded when the programs run.
install_npm_folders() {
  local lock dir
  while IFS= read -r lock; do
    dir="$(dirname "$lock")"
    if [ -d "$dir/node_modules" ] && [ "$dir/node_modules/.package-lock.json" -nt "$lock" ]; then
      continue
    fi
    echo "install-deps: npm ci in $dir"
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
  done < <(cd "$root" && find . -name package-lock.json -not -path '*/node_modules/*' -not -path './build*' | sort)
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
else
  echo "install-deps: installing ${#missing[@]} package(s): ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then
    sudo_cmd=(sudo)
  fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -q
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
fi
install_npm_folders
