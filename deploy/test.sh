#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds if needed, then runs every test (unit and multi-process integration) with ctest.
# Extra arguments go to ctest, e.g. -L unit or -R tracker.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/deploy/build.sh"
cd "$root/${PANOPTES_BUILD_DIR:-build}"
trap 'bash "$root/deploy/dds-shm-clean.sh"' EXIT
# A first run in a new build directory has no cost data, so ctest would start tests in the order
# they are declared and leave the long live tests for the end. Seed it with measured seconds
# (tests/ctest_costs.txt; regenerate with tests/tools/ctest_costs.sh after a full run) so the
# long, locked tests start first (docs/testing.md, "What runs in parallel"); ctest refines it.
if [ ! -s Testing/Temporary/CTestCostData.txt ] && [ -s "$root/tests/ctest_costs.txt" ]; then
  mkdir -p Testing/Temporary
  grep -v '^#' "$root/tests/ctest_costs.txt" >Testing/Temporary/CTestCostData.txt
  echo "---" >>Testing/Temporary/CTestCostData.txt
fi
# On a failure the digest repeats, last, what failed inside each failed test: CI shows only the tail.
ctest --output-on-failure -j "$(nproc)" "$@" || {
  rc=$?
  python3 "$root/tests/tools/failure_digest.py" . || true
  exit "$rc"
}
