#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `estimator_node calibrate capture` live (issue 6): six camera_nodes replay simulated wand
# features over DDS (loopback profile) on a common epoch; the capture must record every camera's
# frames, close to all that were sent, and `calibrate solve` must succeed on the recording.
source "$(dirname "$0")/lib.sh"
en="$bin/estimator_node"
# A DDS domain of its own: benchmarks and other tests on this machine publish cam0.. too (found:
# a latency benchmark's cameras doubled cam0-cam3 in the recording).
export PANOPTES_DOMAIN=$(( 100 + $$ % 100 ))

cp "$source_dir/deploy/scenes/wand_room.yaml" "$work/room.yaml"
expect_exit 0 "simulate wand features" -- "$bin/panoptes_sim" features --scene "$work/room.yaml" --out-dir "$work/wand" --duration 6
cameras=(cam0 cam1 cam2 cam3 cam4 cam5)

# The capture starts first (it also serves the time base) and outlasts the replay.
epoch=$(( ($(date +%s) + 4) * 1000000000 ))
"$en" calibrate capture --out "$work/capture.jsonl" --duration 14 --time-service \
  >"$work/capture.out" 2>"$work/capture.err" &
capture=$!
pids+=("$capture")
for camera in "${cameras[@]}"; do
  "$bin/camera_node" --source "features:$work/wand/$camera.jsonl" --sim-epoch-ns "$epoch" --duration 12 --quiet \
    >"$work/$camera.log" 2>&1 &
  pids+=("$!")
done
timeout 30 tail --pid="$capture" -f /dev/null
wait "$capture"
rc=$?
[ "$rc" -eq 0 ] && pass "calibrate capture exited cleanly" || { fail "calibrate capture exit $rc"; tail -5 "$work/capture.err"; }
cat "$work/capture.out"
tail -2 "$work/capture.err"

# Every camera recorded, with (nearly) every frame it published (camera_node's own count: under load
# it may drop frames in its detection queue before publishing, which is not the capture's doing).
for camera in "${cameras[@]}"; do
  recorded=$(grep -c . "$work/wand/$camera.jsonl")
  sent=$(sed -n 's/.*stopped after \([0-9]*\) frames.*/\1/p' "$work/$camera.log")
  got=$(grep -c "\"camera_id\":\"$camera\"" "$work/capture.jsonl" || true)
  echo "$camera: $recorded in the file, published ${sent:-?}, captured $got"
  [ "${sent:-0}" -ge $(( recorded * 3 / 4 )) ] || fail "$camera published only ${sent:-no} of $recorded frames"
  if [ "$got" -ge $(( ${sent:-1} * 99 / 100 )) ] && [ "$got" -le "${sent:-0}" ]; then
    pass "$camera: $got of $sent frames captured"
  else
    fail "$camera: $got of $sent frames captured"
  fi
done
grep -q "from 6 cameras" "$work/capture.out" && pass "the summary counts 6 cameras" || fail "summary lacks 6 cameras"

# The recording solves.
expect_exit 0 "calibrate solve on the captured file" -- "$en" calibrate solve --cameras "$work/wand/calibration.yaml" \
  --in-features "$work/capture.jsonl" --wand 0,0.18,0.5 --out "$work/cal.yaml" --time-offsets
head -12 "$work/last.out"
grep -q "calibrated 6 of 6 cameras" "$work/last.out" && pass "all 6 cameras calibrated from the capture" ||
  fail "not all cameras calibrated from the capture"
finish
