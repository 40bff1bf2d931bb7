#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Writes tests/ctest_costs.txt: every test's seconds from a build directory's ctest cost data
# (Testing/Temporary/CTestCostData.txt, written by a full `ctest -j2` run), which deploy/test.sh
# copies into a new build directory so that its first run starts the long tests first.
#   bash tests/tools/ctest_costs.sh BUILD_DIR
set -euo pipefail
build_dir="${1:?usage: ctest_costs.sh BUILD_DIR}"
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
data="$build_dir/Testing/Temporary/CTestCostData.txt"
[ -s "$data" ] || { echo "ctest_costs.sh: $data: missing or empty (run the suite first)" >&2; exit 2; }
{
  echo "# SPDX-License-Identifier: Apache-2.0"
  echo "# ctest seconds per test (name, runs, seconds), from tests/tools/ctest_costs.sh; read by deploy/test.sh."
  awk '$0 == "---" {exit} NF == 3 {printf "%s 1 %.1f\n", $1, $3}' "$data" | sort
} >"$source_dir/tests/ctest_costs.txt"
echo "wrote $source_dir/tests/ctest_costs.txt ($(grep -vc '^#' "$source_dir/tests/ctest_costs.txt") tests)"
