#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds if needed, then runs every test (unit and multi-process integration) with ctest.
# Extra arguments go to ctest, e.g. -L unit or -R tracker.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/deploy/build.sh"
cd "$root/${PANOPTES_BUILD_DIR:-build}"
trap 'bash "$root/deploy/dds-shm-clean.sh"' EXIT
ctest --output-on-failure -j "$(nproc)" "$@"
