#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Writes a benchmark's new figure into its row of docs/bench-results/<capability>.json (date, commit
# and machine filled in), then regenerates docs/benchmarks.md's tables (tests/bench/report.sh).
# Examples:
#   build/bin/bench_latency --json > l1.json; ...   # three runs
#   tests/bench/record_result.sh latency bodypose_p99 --from-json l1.json l2.json l3.json
#   tests/bench/record_result.sh suite readme_warm --value 11.4 --command './deploy/test.sh'
# The figure is the median of the runs given; the row's 'extract' names the JSON field unless --field
# does. Run with --help for every option.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
if [[ "${1:-}" == -h || "${1:-}" == --help ]]; then
  exec python3 "$here/bench_results.py" record --help
fi
exec python3 "$here/bench_results.py" record "$@"
