#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs every Debian 12 package Panoptes needs to build, test and run the demo.
# Idempotent and non-interactive: packages already present are not touched.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache git
  libfastrtps-dev fastddsgen fastdds-tools
  libopencv-dev libeigen3-dev libceres-dev
  opencv-doc
  libaravis-dev aravis-tools libusb-1.0-0-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format clang-tidy python3-yaml
  cyclonedds-dev cyclonedds-tools pybind11-dev python3-dev python3-numpy python3-matplotlib
  iproute2 procps nftables
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} package(s): ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
