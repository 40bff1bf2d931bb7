#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Flakiness check (issue 37; docs/deployment.md, "Before landing an integration test"): runs the
# selected tests N times with `ctest -j2` (as ./deploy/test.sh runs them on a 2-core machine),
# optionally with a CPU load on every core, and reports each test's pass rate: a table on stdout
# and a JSON document (--json). Run it on every new or changed integration test before it lands;
# a test that does not pass N of N here will fail on somebody's machine.
#
#   bash tests/stress/flakiness.sh BUILD_DIR [options]
#     --runs N         runs (10)
#     --load           one busy loop per core (nproc) at the tests' priority, for the whole check
#     --load-cmd CMD   a load of your own instead (e.g. a build: "ninja -C /tmp/other -j2"); it is
#                      started again whenever it ends, and stopped at the end
#     -R REGEX         ctest's test selection (^integration\.); -L/-E pass through as -L/-E
#     -L LABEL, -E REGEX
#     -j N             ctest's parallelism (2)
#     --json FILE      the report as JSON (BUILD_DIR/flakiness.json)
#     --logs DIR       every run's ctest output and JUnit file (BUILD_DIR/flakiness-logs)
#     --resume         add N runs to those already in --logs (the same build, e.g. a check that did
#                      not fit one sitting); the report covers every run there
# Exit status: 0 when every test that ran passed in every run, 1 otherwise.
# Skipped tests (exit 77: no root, no browser, ...) are counted apart and do not lower the rate.
set -uo pipefail
case "${1:-}" in -h | --help) sed -n '3,22p' "$0"; exit 0 ;; esac
build_dir="$(cd "${1:?usage: flakiness.sh BUILD_DIR [--runs N] [--load] [-R REGEX] ...}" && pwd)" ||
  { echo "flakiness.sh: no build directory '$1' (--help)" >&2; exit 2; }
shift
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
runs=10 load=0 load_cmd="" jobs=2 resume=0
select=(-R '^integration\.')
json="$build_dir/flakiness.json"
logs="$build_dir/flakiness-logs"
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --load) load=1; shift ;;
    --resume) resume=1; shift ;;
    --load-cmd) load=1; load_cmd="$2"; shift 2 ;;
    -R) select=(-R "$2"); shift 2 ;;
    -L | -E) select+=("$1" "$2"); shift 2 ;;
    -j) jobs="$2"; shift 2 ;;
    --json) json="$2"; shift 2 ;;
    --logs) logs="$2"; shift 2 ;;
    -h | --help) sed -n '3,22p' "$0"; exit 0 ;;
    *) echo "flakiness.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
case "$runs" in '' | *[!0-9]* | 0) echo "flakiness.sh: --runs must be a positive whole number (got '$runs')" >&2; exit 2 ;; esac
mkdir -p "$logs"
first=1
if [ "$resume" -eq 1 ]; then
  while [ -e "$logs/run$first.log" ]; do first=$((first + 1)); done
  echo "resuming after $((first - 1)) run(s) in $logs"
else
  rm -f "$logs"/run*.log "$logs"/run*.xml "$logs/run_seconds.txt"
fi
last=$((first + runs - 1))

# The load: one busy loop per core, or the user's command restarted whenever it ends. Each runs in
# a process group of its own so that it can be stopped with everything it started.
load_pids=()
stop_load() {
  for pid in "${load_pids[@]}"; do kill -TERM -- "-$pid" 2>/dev/null; done
  for pid in "${load_pids[@]}"; do wait "$pid" 2>/dev/null; done
  load_pids=()
}
trap stop_load EXIT
if [ "$load" -eq 1 ]; then
  if [ -n "$load_cmd" ]; then
    setsid bash -c "while :; do $load_cmd >/dev/null 2>&1; done" &
    load_pids+=("$!")
  else
    for _ in $(seq "$(nproc)"); do
      setsid bash -c 'while :; do :; done' &
      load_pids+=("$!")
    done
  fi
  echo "load: ${load_cmd:-$(nproc) busy loops} (pids ${load_pids[*]})"
fi

started=$(date -u +%Y-%m-%dT%H:%M:%SZ)
for run in $(seq "$first" "$last"); do
  t0=$(date +%s)
  (cd "$build_dir" && ctest -j "$jobs" "${select[@]}" --output-on-failure --output-junit "$logs/run$run.xml") \
    >"$logs/run$run.log" 2>&1
  bash "$source_dir/deploy/dds-shm-clean.sh" >/dev/null 2>&1
  echo "$run $(($(date +%s) - t0))" >>"$logs/run_seconds.txt"
  echo "run $run/$last: $(grep -E '^[0-9]+% tests passed' "$logs/run$run.log" || echo 'no summary (see log)') ($(($(date +%s) - t0)) s)"
done
stop_load

python3 - "$logs" "$last" "$json" "$load" "$load_cmd" "$jobs" "$started" "${select[*]}" <<'PY'
import json, sys, xml.etree.ElementTree as ET
logs, runs, out, load, load_cmd, jobs, started, selection = sys.argv[1:]
runs = int(runs)
tests = {}
for run in range(1, runs + 1):
    try:
        suite = ET.parse(f"{logs}/run{run}.xml").getroot()
    except (OSError, ET.ParseError) as error:
        print(f"run {run}: no JUnit report ({error}); counted as no result", file=sys.stderr)
        continue
    for case in suite.iter("testcase"):
        entry = tests.setdefault(case.get("name"), {"passed": 0, "failed": 0, "skipped": 0, "failed_runs": [], "seconds": []})
        status = case.get("status", "")
        if case.find("skipped") is not None or status in ("notrun", "disabled"):
            entry["skipped"] += 1
        elif case.find("failure") is not None or case.find("error") is not None or status == "fail":
            entry["failed"] += 1
            entry["failed_runs"].append(run)
        else:
            entry["passed"] += 1
        entry["seconds"].append(float(case.get("time", 0) or 0))
rows = []
for name, e in sorted(tests.items()):
    ran = e["passed"] + e["failed"]
    rows.append({"test": name, "runs": ran, "passed": e["passed"], "failed": e["failed"], "skipped": e["skipped"],
                 "pass_rate": round(e["passed"] / ran, 3) if ran else None, "failed_runs": e["failed_runs"],
                 "seconds_max": round(max(e["seconds"], default=0), 1)})
try:
    run_seconds = [int(line.split()[1]) for line in open(f"{logs}/run_seconds.txt")]
except (OSError, IndexError, ValueError):
    run_seconds = []
report = {"started": started, "runs": runs, "run_seconds": run_seconds, "ctest_jobs": int(jobs), "selection": selection,
          "load": (load_cmd or "busy loop per core") if load == "1" else None, "tests": rows,
          "flaky_or_failing": [r["test"] for r in rows if r["failed"]]}
json.dump(report, open(out, "w"), indent=1)
width = max([len(r["test"]) for r in rows] + [4])
print(f"\n| {'test'.ljust(width)} | passed | failed | skipped | pass rate | slowest s |")
print(f"| {'-' * width} | ---: | ---: | ---: | ---: | ---: |")
for r in rows:
    rate = "-" if r["pass_rate"] is None else f"{r['passed']}/{r['runs']}"
    print(f"| {r['test'].ljust(width)} | {r['passed']} | {r['failed']} | {r['skipped']} | {rate} | {r['seconds_max']} |")
print(f"\n{runs} run(s), ctest -j{jobs} {selection}, load: {report['load'] or 'none'}; JSON: {out}")
if report["flaky_or_failing"]:
    print("not N of N: " + ", ".join(report["flaky_or_failing"]) + f" (logs: {logs}/runK.log)")
sys.exit(1 if report["flaky_or_failing"] else 0)
PY
