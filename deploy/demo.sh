#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job: builds if needed, then runs the simulated multi-camera demo over DDS (loopback).
# Extra arguments go to panoptes_demo (see build/bin/panoptes_demo --help), e.g. --duration 60.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/deploy/build.sh"
trap 'bash "$root/deploy/dds-shm-clean.sh"' EXIT
"$root/${PANOPTES_BUILD_DIR:-build}/bin/panoptes_demo" "$@"
