#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Writes tests/ctest_costs.txt: every test's seconds from a build directory's ctest cost data
# (Testing/Temporary/CTestCostData.txt, written by a full `ctest -j2` run), which deploy/test.sh
# copies into a new build directory so that its first run starts the long tests first.
# Tests with an explicit COST property (the serial and locked live tests, tests/CMakeLists.txt) are
# left out: ctest orders them by that COST, and its cost data for them is a running average of the
# explicit value and the measured seconds, not seconds.
#   bash tests/tools/ctest_costs.sh BUILD_DIR
set -euo pipefail
build_dir="${1:?usage: ctest_costs.sh BUILD_DIR}"
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
data="$build_dir/Testing/Temporary/CTestCostData.txt"
[ -s "$data" ] || { echo "ctest_costs.sh: $data: missing or empty (run the suite first)" >&2; exit 2; }
explicit="$(mktemp)"
trap 'rm -f "$explicit"' EXIT
(cd "$build_dir" && ctest --show-only=json-v1) | python3 -c '
import json, sys
for test in json.load(sys.stdin)["tests"]:
    if any(p["name"] == "COST" for p in test.get("properties", [])):
        print(test["name"])
' >"$explicit"
{
  echo "# SPDX-License-Identifier: Apache-2.0"
  echo "# ctest seconds per test (name, runs, seconds), from tests/tools/ctest_costs.sh; read by deploy/test.sh."
  awk 'FNR == NR {skip[$1] = 1; next} $0 == "---" {exit} NF == 3 && !($1 in skip) {printf "%s 1 %.1f\n", $1, $3}' \
    "$explicit" "$data" | sort
} >"$source_dir/tests/ctest_costs.txt"
echo "wrote $source_dir/tests/ctest_costs.txt ($(grep -vc '^#' "$source_dir/tests/ctest_costs.txt") tests," \
  "$(wc -l <"$explicit") with an explicit COST left out)"
