#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Inside-out mode end to end (issue 21, docs/inside_out.md): the head-mounted camera of
# deploy/scenes/inside_out.yaml, offline (features JSONL -> estimator_node --landmarks -> Pose
# JSONL) and live over DDS (camera_node --source sim: rendering the moving camera's images and
# detecting their blobs -> estimator_node -> rt/panoptes/bodies and Pose JSONL), judged against the rig's ground truth: position RMSE <= 1 mm,
# orientation <= 0.05 deg, first pose within 0.2 s of the first frame, no wrong pose. Bad landmark
# files and a moving camera without landmarks exit 2 naming the file and entry. With the fixed pair
# that sees the headset's markers, the fused pose beats inside-out alone.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/inside_out.yaml"

# first_pose_delay_ms FEATURES POSES: ms from the camera's first frame to the first pose.
first_pose_delay_ms() {
  local first_frame first_pose
  # Not jq: it reads integers as doubles, and stamps need 19 digits.
  first_frame=$(head -1 "$1" | grep -o '"stamp_ns":[0-9]*' | cut -d: -f2)
  first_pose=$(head -1 "$2" | grep -o '"stamp_ns":[0-9]*' | cut -d: -f2)
  echo $(((first_pose - first_frame) / 1000000))
}

# --- offline --------------------------------------------------------------------------------------
expect_exit 0 "simulate the head camera (20 s)" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
grep -q "moving: true" "$work/sim/calibration.yaml" && grep -q 'rig: "headset"' "$work/sim/calibration.yaml" &&
  pass "the calibration marks the head camera moving on rig headset" || fail "calibration lacks moving/rig"
[ -s "$work/sim/landmarks.yaml" ] && pass "landmarks.yaml written" || fail "no landmarks.yaml"
grep -q '"name":"headset"' <(head -1 "$work/sim/truth.jsonl") && pass "truth.jsonl carries the rig's pose" ||
  fail "no rig in truth.jsonl"
expect_exit 0 "offline estimator in inside-out mode" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --landmarks "$work/sim/landmarks.yaml" --in-features "$work/sim/head.jsonl" --no-dds --out-poses "$work/poses.jsonl"
expect_stderr_contains "inside-out: camera 'head' carries rig 'headset', tracked from 20 landmarks in 5 groups" \
  "the set-up is reported"
expect_stderr_contains "acquisitions 1 (last from" "one cold start, never lost"
# The moving camera's frames count as used in the usage figures (status, console), not as dropped.
util=$(grep -o "camera head: frames [0-9]* used [0-9]* .*utilisation [0-9.]*" "$work/last.err" | grep -o "utilisation [0-9.]*" | grep -o "[0-9.]*$")
python3 -c "import sys; sys.exit(0 if ${util:-0} >= 0.99 else 1)" && pass "head camera utilisation $util" ||
  fail "head camera utilisation '${util}' (want >= 0.99)"
grep -q '"body":"headset"' "$work/poses.jsonl" && pass "poses are published under the rig's name" || fail "no headset poses"
expect_exit 0 "offline poses: <= 1 mm, <= 0.05 deg, >= 99% of the time tracked" -- "$bin/panoptes_eval" --scene "$scene" \
  --poses "$work/poses.jsonl" --warmup 0.5 --require-pose-rmse-mm 1.0 --require-pose-rmse-deg 0.05 \
  --require-pose-tracked 0.99
cat "$work/last.out"
expect_exit 0 "no wrong pose from the cold start on" -- "$bin/panoptes_eval" --scene "$scene" --poses "$work/poses.jsonl" \
  --warmup 0 --require-no-wrong-poses
delay=$(first_pose_delay_ms "$work/sim/head.jsonl" "$work/poses.jsonl")
echo "offline: first pose ${delay} ms after the first frame"
[ "$delay" -le 200 ] && pass "acquired within 0.2 s" || fail "first pose after ${delay} ms"

# --- fused with the fixed outside-in pair that sees the headset's markers --------------------------
rmse_of() { awk '$1 == "headset" { print $2, $4 }' "$1"; }  # position mm, orientation deg
expect_exit 0 "inside-out alone: evaluated" -- "$bin/panoptes_eval" --scene "$scene" --poses "$work/poses.jsonl" --warmup 0.5
cp "$work/last.out" "$work/alone.eval"
expect_exit 0 "offline estimator fusing the fixed pair's view of the headset" -- "$bin/estimator_node" \
  --calibration "$work/sim/calibration.yaml" --landmarks "$work/sim/landmarks.yaml" \
  --in-features "$work/sim/head.jsonl" "$work/sim/fixed0.jsonl" "$work/sim/fixed1.jsonl" --no-dds \
  --out-poses "$work/fused.jsonl"
expect_stderr_contains "rig 'headset' fused with the fixed cameras' view of its 4 markers" "fusion is reported"
expect_stderr_contains "outside-in marker updates" "the summary counts the outside-in updates"
expect_exit 0 "fused poses: no wrong pose, >= 99% tracked" -- "$bin/panoptes_eval" --scene "$scene" \
  --poses "$work/fused.jsonl" --warmup 0.5 --require-pose-tracked 0.99 --require-no-wrong-poses
cat "$work/last.out"
read -r alone_mm alone_deg < <(rmse_of "$work/alone.eval")
read -r fused_mm fused_deg < <(rmse_of "$work/last.out")
echo "inside-out alone: $alone_mm mm, $alone_deg deg; fused: $fused_mm mm, $fused_deg deg"
awk -v a="$alone_mm" -v f="$fused_mm" -v ad="$alone_deg" -v fd="$fused_deg" 'BEGIN { exit !(f < 0.8 * a && fd <= ad) }' &&
  pass "the fused pose is better than inside-out alone" || fail "fusion did not help"

# --- bad input ------------------------------------------------------------------------------------
run_bad() {  # run_bad DESCRIPTION EXPECTED-TEXT -- estimator arguments...
  local what="$1" text="$2"
  shift 3
  expect_exit 2 "$what" -- "$bin/estimator_node" --in-features "$work/sim/head.jsonl" --no-dds \
    --out-poses "$work/x.jsonl" "$@"
  expect_stderr_contains "$text" "the error names it: $text"
}
printf 'landmarks:\n  - {name: a, markers: [[0,0,3],[1,0,3],[0,1,3]]}\n  - {name: a, position: [2,2,3]}\n' >"$work/dup.yaml"
run_bad "landmarks with duplicate ids" "dup.yaml: landmarks[1].name: duplicate landmark id 'a'" -- \
  --calibration "$work/sim/calibration.yaml" --landmarks "$work/dup.yaml"
run_bad "a missing landmarks file" "$work/absent.yaml" -- --calibration "$work/sim/calibration.yaml" \
  --landmarks "$work/absent.yaml"
run_bad "a moving camera without landmarks" "camera 'head' is moving: true" -- \
  --calibration "$work/sim/calibration.yaml" --bodies "$source_dir/deploy/scenes/bodies.yaml"

# --- live over DDS: the simulator renders the head camera's images, camera_node detects the blobs --
epoch=$(( ($(date +%s) + 3) * 1000000000 ))
"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --landmarks "$scene" \
  --out-poses "$work/live_poses.jsonl" --duration 10 --status-period 1 >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
# The rig is described to clients (rt/panoptes/body_descriptions, kind "rig").
python=$(cat "$build_dir/python/INTERPRETER" 2>/dev/null)
if [ -n "$python" ] && [ -f "$build_dir/python/panoptes/__init__.py" ]; then
  PYTHONPATH="$build_dir/python" timeout 20 "$python" - >"$work/descriptions.txt" 2>&1 <<'PYTHON' &
import time, panoptes
with panoptes.Client() as client:
    deadline = time.monotonic() + 8
    while time.monotonic() < deadline and not client.body_descriptions():
        time.sleep(0.1)
    print(" ".join(f"{d.name}:{d.kind}" for d in client.body_descriptions()))
PYTHON
  describer=$!
  pids+=("$describer")
fi
"$bin/camera_node" --source "sim:$scene#head" --sim-epoch-ns "$epoch" --duration 8 --quiet >"$work/camera.log" 2>&1 &
pids+=("$!")
timeout 40 tail -s 0.05 --pid="$estimator" -f /dev/null
wait "$estimator"
rc=$?
[ "$rc" -eq 0 ] && pass "live estimator exited cleanly" || { fail "live estimator exit $rc"; tail -20 "$work/estimator.log"; }
grep "inside-out" "$work/estimator.log"
if [ -n "${describer:-}" ]; then
  wait "$describer"
  grep -qx "headset:rig" "$work/descriptions.txt" && pass "the rig is in body_descriptions as kind rig" ||
    { fail "body descriptions: $(cat "$work/descriptions.txt")"; }
fi
live=$(grep -c '"body":"headset"' "$work/live_poses.jsonl" || true)
echo "live poses: $live"
[ "${live:-0}" -gt 400 ] && pass "headset poses published live" || fail "too few live poses ($live)"
expect_exit 0 "live poses: <= 1 mm, <= 0.05 deg, no wrong pose" -- "$bin/panoptes_eval" --scene "$scene" \
  --poses "$work/live_poses.jsonl" --epoch-ns "$epoch" --warmup 0.5 --require-pose-rmse-mm 1.0 \
  --require-pose-rmse-deg 0.05 --require-no-wrong-poses
cat "$work/last.out"
finish
