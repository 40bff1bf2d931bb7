#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# lint.bench_report: docs/benchmarks.md's tables equal what tests/bench/report.sh generates from the
# committed docs/bench-results/*.json; report.sh is idempotent; record_result.sh writes a row that
# the report then shows; and a malformed record is refused (exit 2) naming the file and the field.
# Usage: bench_report.sh <source dir>
set -euo pipefail
src="${1:?usage: bench_report.sh <source dir>}"
report="$src/tests/bench/report.sh"
record="$src/tests/bench/record_result.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failures=0
check() {  # check <description> <command...>: the command must succeed
  local what="$1"; shift
  if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; failures=$((failures + 1)); fi
}

# 1. The committed tables are current.
check "committed docs/benchmarks.md matches docs/bench-results" bash "$report" --check

# A copy of docs/ to change freely (the details links are checked against it).
cp -r "$src/docs" "$work/docs"
docs="$work/docs"
results="$docs/bench-results"

# 2. Idempotent: regenerating the current tables changes nothing, twice.
bash "$report" --results "$results" --doc "$docs/benchmarks.md" >/dev/null
bash "$report" --results "$results" --doc "$docs/benchmarks.md" >/dev/null
check "report.sh is idempotent" cmp -s "$docs/benchmarks.md" "$src/docs/benchmarks.md"

# 3. A changed record makes --check fail until the tables are regenerated.
python3 - "$results/detector.json" <<'PY'
import json, sys
data = json.load(open(sys.argv[1]))
data["rows"][0]["value"] = 0.25
json.dump(data, open(sys.argv[1], "w"), indent=2, ensure_ascii=False)
PY
stale_fails() { ! bash "$report" --check --results "$results" --doc "$docs/benchmarks.md" >/dev/null 2>&1; }
check "--check fails when a record changed" stale_fails
bash "$report" --results "$results" --doc "$docs/benchmarks.md" >/dev/null
check "the regenerated table shows the new figure" grep -q '\*\*0.25×\*\*' "$docs/benchmarks.md"

# 4. record_result.sh: a figure from benchmark JSON outputs (median of the runs), date, commit, machine.
printf 'progress line\n{"end_to_end_ms": {"p50": 0.2, "p99": 0.61}}\n' >"$work/l1.json"
printf '{"end_to_end_ms": {"p50": 0.2, "p99": 0.55}}\n' >"$work/l2.json"
printf '{"end_to_end_ms": {"p50": 0.2, "p99": 0.70}}\n' >"$work/l3.json"
PANOPTES_BENCH_RESULTS="$results" PANOPTES_BENCH_DOC="$docs/benchmarks.md" bash "$record" latency bodypose_p99 \
  --from-json "$work/l1.json" "$work/l2.json" "$work/l3.json" --commit 0123456789 --date 2030-01-02 \
  --machine "test machine" >/dev/null
recorded() {
  python3 - "$results/latency.json" <<'PY'
import json, sys
row = next(r for r in json.load(open(sys.argv[1]))["rows"] if r["id"] == "bodypose_p99")
assert row["value"] == 0.61 and row["runs"] == [0.61, 0.55, 0.7], row
assert row["date"] == "2030-01-02" and row["commit"] == "0123456789" and "carried_over" not in row, row
PY
}
check "record_result.sh writes the median of the runs and drops carried_over" recorded
check "the table shows the recorded row" grep -q '\*\*0.61 ms\*\* (3 runs: 0.55–0.7).*2030-01-02 | `0123456789`' \
  "$docs/benchmarks.md"
check "the tables are current after record_result.sh" \
  bash "$report" --check --results "$results" --doc "$docs/benchmarks.md" >/dev/null
printf '{"cameras": 32, "console": {"console_cpu_percent": 5.5, "websocket_bytes_per_s": 210400}}\nflood: done\n' \
  >"$work/c.json"
PANOPTES_BENCH_RESULTS="$results" PANOPTES_BENCH_DOC="$docs/benchmarks.md" bash "$record" console \
  bandwidth_32_cameras --from-json "$work/c.json" --commit abcdef0 --machine "test machine" >/dev/null
check "record_result.sh scales an extracted figure ('websocket_bytes_per_s * 0.001')" \
  grep -q '\*\*210.4 kB/s\*\*.*`abcdef0`' "$docs/benchmarks.md"

# 5. Malformed records are refused with exit 2, naming the file and the field (in one Python process).
check "malformed records are refused, named" python3 "$src/tests/lint/bench_report_refusals.py" "$results" \
  "$docs/benchmarks.md" "$work"
# ... and through report.sh, the command users run: its exit code and message.
rm -rf "$work/bad" && cp -r "$results" "$work/bad" && printf '{"rows": [' >"$work/bad/broken.json"
broken_json() {
  local out rc=0
  out="$(bash "$report" --check --results "$work/bad" --doc "$docs/benchmarks.md" 2>&1)" || rc=$?
  [[ $rc -eq 2 && "$out" == *"$work/bad/broken.json: not valid JSON"* ]]
}
check "report.sh refuses a file that is not JSON with exit 2, naming it" broken_json

if ((failures)); then
  echo "$failures check(s) failed"
  exit 1
fi
echo "all checks passed"
