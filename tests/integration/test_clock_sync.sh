#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Clock synchronisation over DDS (issue 4, item 6; architecture.md "Time"): 4 simulated
# camera_nodes whose clocks are skewed by ±50 ms and drift by ±200 ppm (--clock-skew, plus a
# scene clock_offset on one camera) and one estimator_node serving the time. Every node's clock is
# the host's wall clock plus a known skew, and the estimator's clock is that same wall clock, so
# the truth is exact: after 5 s each camera's estimated offset must be within 0.2 ms of it, the
# tracks must be as accurate as with perfect clocks, and no camera may be starved.
source "$(dirname "$0")/lib.sh"
# A domain of our own (lib.sh): other tests on this host must not answer our requests.

# The demo's four cameras; cam2's own clock is 4 ms ahead in the scene, which the node must treat
# as part of its clock and correct as well.
scene="$work/scene.yaml"
python3 - "$source_dir/deploy/scenes/demo.yaml" "$scene" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
text, n = re.subn(r"(    rate: 90\n)", r"\1    clock_offset: 0.004\n", text)
assert n == 1, "demo.yaml changed: cam2's rate line not found"
open(sys.argv[2], "w").write(text)
PY
declare -A skews=([cam0]="50,200" [cam1]="-50,-200" [cam2]="20,-150" [cam3]="-35,120")
frames_s=8
# Scene time 0 two seconds after start, as the demo does: frames begin once the processes run.
epoch=$(( ($(date +%s) + 3) * 1000000000 ))

"$bin/estimator_node" --duration $((frames_s + 6)) --out-tracks "$work/tracks.jsonl" --status-period 1 \
  >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
for id in cam0 cam1 cam2 cam3; do
  "$bin/camera_node" --source "sim:$scene#$id" --sim-epoch-ns "$epoch" --duration $((frames_s + 3)) \
    --clock-skew "${skews[$id]}" >"$work/$id.log" 2>&1 &
  pids+=("$!")
done
camera_pids=("${pids[@]:1}")

# While they run: the status each camera publishes carries the sync counters.
timeout 20 "$bin/panoptes_ctl" status --count 12 --timeout 15 >"$work/status.jsonl" 2>"$work/status.err"
python3 - "$work/status.jsonl" <<'PY' && pass "camera_status carries the sync counters, nothing published unsynchronised" || fail "camera_status: $(tail -2 "$work/status.jsonl")"
import json, sys
seen = {}
for line in open(sys.argv[1]):
    status = json.loads(line)
    seen[status["camera_id"]] = status["counters"]
assert set(seen) == {"cam0", "cam1", "cam2", "cam3"}, seen.keys()
for camera, counters in seen.items():
    assert "sync_lost" in counters and counters.get("unsynchronised", 0) == 0, (camera, counters)
PY

for pid in "${camera_pids[@]}"; do
  timeout 30 tail -s 0.05 --pid="$pid" -f /dev/null
  wait "$pid" || fail "camera_node (pid $pid) exit $?"
done
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null
wait "$estimator" && pass "estimator_node stopped cleanly" || fail "estimator_node exit $?"
# Issue 32: once every camera has stopped, the estimator deletes the tracks no frame keeps alive
# (they stayed confirmed in its status for as long as it ran). It runs 3 s past the cameras.
last_tracks=$(grep -o 'tracks [0-9]*+[0-9]* coasting' "$work/estimator.log" | tail -1)
grep -q "no frame for [0-9]* ms: [0-9]* track(s) deleted" "$work/estimator.log" && [ "$last_tracks" = "tracks 0+0 coasting" ] &&
  pass "after the cameras stopped, the estimator deleted its tracks (last status: $last_tracks)" ||
  fail "tracks outlived the cameras: $(grep -E 'tracks [0-9]|no frame for' "$work/estimator.log" | tail -3)"

# Every second each camera logs its estimate against the truth:
#   clock sync at <t> s: offset X ms (true Y ms, error E us), drift D ppm (true T), ...
for id in cam0 cam1 cam2 cam3; do
  log="$work/$id.log"
  grep -E "clock sync(hronised)?( at|:| after)" "$log" | sed 's/^/  /'
  python3 - "$log" "$id" "${skews[$id]}" <<'PY' && pass "$id: every estimate after 5 s within 0.2 ms of the truth" || fail "$id: clock sync residual"
import re, sys
log, camera, skew = sys.argv[1], sys.argv[2], sys.argv[3]
text = open(log).read()
checked = 0
worst = 0.0
for t, offset, truth, error in re.findall(
        r"clock sync at ([\d.]+) s: offset (-?[\d.]+) ms \(true (-?[\d.]+) ms, error ([-+][\d.]+) us\)", text):
    t, offset, truth, error = float(t), float(offset), float(truth), float(error)
    # offset and truth are rounded to 1 us each and error to 0.1 us: they agree within 1.05 us.
    if abs((offset - truth) * 1e3 - error) > 1.1:
        sys.exit(f"{camera}: inconsistent line at {t} s")
    if t >= 5.0:
        checked += 1
        worst = max(worst, abs(error))
# The first truth logged (on synchronising, within 2 s of start) must be the skew the node was
# told, plus cam2's 4 ms scene offset, plus at most 2 s of drift: the truth is right.
offset_ms, drift_ppm = (float(v) for v in skew.split(","))
expected = offset_ms + (4.0 if camera == "cam2" else 0.0)
first_truth = re.search(r"\(true (-?[\d.]+) ms", text)
if first_truth is None or abs(float(first_truth.group(1)) - expected) > abs(drift_ppm) * 2e-3 + 0.01:
    sys.exit(f"{camera}: true offset {first_truth and first_truth.group(1)} ms, expected about {expected} ms")
final = re.search(r"clock sync: offset (-?[\d.]+) ms \(true (-?[\d.]+) ms, error ([-+][\d.]+) us\), "
                  r"drift (-?[\d.]+) ppm \(true (-?[\d.]+)\)", text)
if final is None:
    sys.exit(f"{camera}: no final clock sync line")
print(f"  {camera}: {checked} estimates after 5 s, worst error {worst:.1f} us; final error "
      f"{float(final.group(3)):+.1f} us, drift {final.group(4)} ppm (true {final.group(5)})")
if checked < 3:
    sys.exit(f"{camera}: only {checked} estimates after 5 s")
if worst >= 200.0:
    sys.exit(f"{camera}: residual {worst:.1f} us >= 200 us")
if abs(float(final.group(4)) - drift_ppm) > 50.0:
    sys.exit(f"{camera}: drift {final.group(4)} ppm, true {drift_ppm}")
PY
  grep -q "frames held 0, unsynchronised 0" "$log" && pass "$id: synchronised before its first frame" ||
    fail "$id: frames held or published unsynchronised: $(grep -o 'frames held.*' "$log")"
done

# No camera starved: the estimator used >= 95% of every camera's frames.
usage=$(grep -h 'estimator_node: camera .*utilisation' "$work/estimator.log" || true)
if [ -n "$usage" ]; then
  echo "$usage"
  [ "$(echo "$usage" | wc -l)" -eq 4 ] && pass "usage reported for 4 cameras" || fail "usage lines: $usage"
  echo "$usage" | awk '{for (i = 1; i < NF; ++i) if ($i == "utilisation") u = $(i + 1); if (u < 0.95) bad = 1}
    END {exit bad}' && pass "every camera's utilisation >= 0.95" || fail "a camera's utilisation is below 0.95"
else
  # TODO(issue 4): estimator_node prints one usage line per camera at exit; require it once it
  # always does.
  echo "note: estimator_node printed no per-camera usage; utilisation not checked"
fi

# Tracking on the corrected stamps as accurate as the demo's targets with perfect clocks.
expect_exit 0 "tracks: RMSE < 2 mm, tracked >= 95%, no ID switch" -- "$bin/panoptes_eval" --scene "$scene" \
  --tracks "$work/tracks.jsonl" --epoch-ns "$epoch" --warmup 1 --require-rmse-mm 2 --require-tracked 0.95 \
  --require-no-id-switches
tail -4 "$work/last.out"
finish
