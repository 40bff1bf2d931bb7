#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Articulated finger chain end to end (issue 21, docs/articulated.md). Offline: the hand scene's
# features -> estimator_node --bodies (type: chain) --out-chains -> tip and joint angles against
# the simulator's truth, every grab/release transition detected and none spurious. Live: four
# camera_nodes replay the same features -> estimator_node publishes rt/panoptes/chains ->
# grab_objects (client library) picks up virtual objects at the fingertip, carries and drops them;
# the Python binding counts the same grab events.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/hand.yaml"
bodies="$source_dir/deploy/scenes/hand_bodies.yaml"

expect_exit 0 "simulate the hand scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
grep -q '"chains":\[{"angles"' "$work/sim/truth.jsonl" && pass "truth.jsonl carries the chain" ||
  fail "no chain truth in truth.jsonl"
expect_exit 0 "offline estimator with the finger chain" -- "$bin/estimator_node" \
  --calibration "$work/sim/calibration.yaml" --bodies "$bodies" --in-features "$work"/sim/c*.jsonl --no-dds \
  --out-chains "$work/chains.jsonl" --quiet
expect_stderr_contains "tracking 1 articulated chain" "the chain is loaded"
expect_stderr_contains "chains (camera frames by status): index tracking" "chain status counts in the summary"
expect_exit 0 "tip within 2 mm RMSE, angles within 2 deg, the 80 ms predicted tip within 5 mm of the truth 80 ms later, >= 95% tracked, every grab/release and none spurious" -- \
  python3 "$source_dir/tests/tools/check_chains.py" --truth "$work/sim/truth.jsonl" --chains "$work/chains.jsonl" \
  --require-tip-rmse-mm 2 --require-angle-rmse-deg 2 --require-predicted-rmse-mm 5 --require-tracked 0.95 --require-events
cat "$work/last.out"
expect_exit 2 "--out-chains without --bodies is refused" -- "$bin/estimator_node" \
  --calibration "$work/sim/calibration.yaml" --in-features "$work/sim/c0.jsonl" --no-dds --out-chains "$work/x.jsonl"
# --- live: four camera_nodes -> estimator_node (rt/panoptes/chains) -> grab_objects ----------------
# Two objects 5 mm from where the offline run saw the first two grabs, one far from the hand.
objects=$(python3 - "$work/chains.jsonl" <<'PY'
import json, sys
grabs = [l for l in map(json.loads, open(sys.argv[1])) if l["type"] == "grab"]
print(" ".join(f"--object {name}={g['tip'][0] + 0.005:.4f},{g['tip'][1]:.4f},{g['tip'][2]:.4f}"
               for name, g in zip(("pawn", "rook"), grabs[:2])) + " --object far=0.5,0.5,1.5")
PY
)
# shellcheck disable=SC2086  # $objects is a list of arguments
"$bin/grab_objects" $objects --radius 0.03 --out "$work/actions.jsonl" --duration 30 --idle-exit 3 \
  >"$work/grab.log" 2>&1 &
grabber=$!
pids+=("$grabber")
python=$(cat "$build_dir/python/INTERPRETER" 2>/dev/null)
if [ -n "$python" ] && [ -f "$build_dir/python/panoptes/__init__.py" ]; then
  PYTHONPATH="$build_dir/python" "$python" - "$work/python.txt" >"$work/python.log" 2>&1 <<'PYTHON' &
import sys, panoptes
kinds, tracking = [], 0
with panoptes.Client() as client:
    while True:
        event = client.wait_for_grab_event(4.0 if kinds else 25.0)
        if event is None:
            break
        kinds.append(event.kind)
        assert event.chain == "index" and len(event.tip) == 3, event
        update = client.latest_chains()
        tracking += update is not None and update.chain("index").status == "tracking"
open(sys.argv[1], "w").write(f"{kinds.count('grab')} {kinds.count('release')} {tracking}\n")
PYTHON
  python_reader=$!
  pids+=("$python_reader")
fi
"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$bodies" --duration 20 \
  --status-period 1 --out-chains "$work/live.jsonl" >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
sleep 1.5
epoch=$(( ($(date +%s) + 3) * 1000000000 ))
replay_cameras "$epoch" 16 c0 c1 c2 c3
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null
wait "$estimator"
rc=$?
[ "$rc" -eq 0 ] && pass "live estimator_node with the chain exited cleanly" || { fail "estimator exit $rc"; tail -5 "$work/estimator.log"; }
grep "chains (camera frames by status)" "$work/estimator.log"
timeout 15 tail -s 0.05 --pid="$grabber" -f /dev/null
wait "$grabber" && pass "grab_objects received chain updates" || { fail "grab_objects exit $?"; }
cat "$work/grab.log"
python3 - "$work" "$(cat "$work/python.txt" 2>/dev/null)" "${python_reader:+yes}" <<'PY' || failures=$((failures + 1))
import json, sys
work, python_counts, python_ran = sys.argv[1], sys.argv[2], sys.argv[3] == "yes"
failures = 0
def check(ok, what):
    global failures
    print(("PASS: " if ok else "FAIL: ") + what)
    failures += 0 if ok else 1
offline = [l for l in map(json.loads, open(f"{work}/chains.jsonl")) if l["type"] != "chain"]
live = [json.loads(l) for l in open(f"{work}/live.jsonl")]
events = [l for l in live if l["type"] != "chain"]
tracked = sum(l["status"] == "tracking" for l in live if l["type"] == "chain")
check(len(events) >= len(offline) - 1 and len(events) >= 6 and tracked > 2000,
      f"live chains: {tracked} tracking records, {len(events)} grab/release events (offline {len(offline)})")
actions = [json.loads(l) for l in open(f"{work}/actions.jsonl")]
check(len(actions) == len(events),
      f"grab_objects saw every event the estimator published ({len(actions)} of {len(events)})")
grabbed = [a for a in actions if a["action"] == "grab"]
released = [a for a in actions if a["action"] == "release"]
check(any(a["object"] == "pawn" for a in grabbed) and any(a["object"] == "rook" for a in grabbed),
      "the fingertip picked up both objects within reach: " + ", ".join(a["object"] for a in grabbed))
check(all(a["object"] != "far" for a in actions), "the far object was never grabbed")
moved = [a["moved_m"] for a in released]
check(len(released) >= 2 and max(moved) > 0.01,
      "objects carried and put down: moved " + ", ".join(f"{m * 1000:.1f} mm" for m in moved))
if python_ran:
    grabs = sum(e["type"] == "grab" for e in events)
    releases = len(events) - grabs
    got = python_counts.split()
    check(len(got) == 3 and got[:2] == [str(grabs), str(releases)] and int(got[2]) == len(events),
          f"the Python binding received every grab event with a tracking chain: '{python_counts}' "
          f"(expected {grabs} {releases} {len(events)})")
sys.exit(1 if failures else 0)
PY
finish
