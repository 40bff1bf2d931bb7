#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Interoperability (issue 15 item 4, docs/interop.md): an application built on Eclipse Cyclone DDS
# (panoptes_cyclone_probe: Cyclone's C API, types from Cyclone's idlc) reads what a live
# estimator_node publishes with Fast DDS: the native rt/panoptes/bodies and rt/panoptes/tracks (and
# rt/panoptes/frames, rt/panoptes/body_descriptions) and the ROS 2 topics (rt/panoptes/<body>/pose
# and /twist, rt/tf, rt/rigid_bodies, rt/markers). Every topic must decode, the ROS 2 topics must
# agree with each other and with the native ones, and the poses and tracks Cyclone decoded must
# score against the simulator's truth as well as the estimator's own output of the same run.
# PANOPTES_CYCLONE_ROS2=0 leaves the ROS 2 topics out.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/clients.yaml"
probe="$bin/panoptes_cyclone_probe"
[ -x "$probe" ] || { fail "$probe is missing (tests/interop, needs cyclonedds-dev)"; finish; }
# Cyclone DDS on loopback only: 127.0.0.1, no multicast, unicast discovery (deploy/dds/cyclone_loopback.xml).
export CYCLONEDDS_URI="file://$source_dir/deploy/dds/cyclone_loopback.xml"
ros2_flag=(--ros2)
[ "${PANOPTES_CYCLONE_ROS2:-1}" = 0 ] && ros2_flag=()

# --- bad arguments ------------------------------------------------------------------------------
expect_exit 2 "the probe rejects a missing --bodies" -- "$probe" --duration 1
expect_stderr_contains "--bodies is required" "the error names the option"
expect_exit 2 "the probe rejects a body name that cannot be a topic name" -- "$probe" --bodies 'he ad'
expect_stderr_contains "--bodies" "the error names the option"
expect_exit 2 "the probe rejects an unreadable Cyclone configuration" -- "$probe" --bodies head --duration 1 \
  --config "file://$work/missing.xml"
expect_exit 1 "with no estimator on the domain the probe decodes nothing and fails" -- "$probe" --bodies head \
  --duration 2 "${ros2_flag[@]}"
grep -q '"ok": false' "$work/last.out" && pass "its summary says so" || fail "no failing summary: $(cat "$work/last.out")"

# --- live: estimator and cameras on Fast DDS, the probe on Cyclone DDS ---------------------------
expect_exit 0 "simulate the clients scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
mkdir -p "$work/cyclone"
epoch=$(($(date +%s) * 1000000000 + 4000000000))
"$probe" --bodies head,tool --duration 17 --out-dir "$work/cyclone" "${ros2_flag[@]}" \
  >"$work/cyclone_summary.json" 2>"$work/cyclone.log" &
probe_pid=$!
pids+=("$probe_pid")
# The per-camera stream (not the live default): the Cyclone reader's poses are compared with --out-poses.
"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$work/sim/bodies.yaml" "${ros2_flag[@]}" \
  --frames per-camera --out-poses "$work/own_poses.jsonl" --out-tracks "$work/own_tracks.jsonl" --duration 15 --status-period 5 \
  >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
replay_cameras "$epoch" 12 c0 c1 c2 c3 c4 c5
# While they run, no UDP socket of theirs is bound to an address outside 127.0.0.0/8. Cyclone DDS binds
# its two unicast receive sockets (the RTPS ports of its participant index) to the wildcard, as it
# always does (Cyclone issues #1923, #2090); it advertises and sends from 127.0.0.1 only
# (docs/interop.md), so those two are accepted, and nothing else.
sleep 8
domain=$PANOPTES_DOMAIN
first_port=$((7400 + 250 * domain + 10))
sockets=$(ss -uanpH 2>/dev/null | grep -E "pid=($probe_pid|$estimator),") || true
outside=$(echo "$sockets" | awk -v probe="pid=$probe_pid," -v first="$first_port" 'NF {
  n = split($4, local, ":"); address = local[1]; port = local[n]
  if (address ~ /^127\./) next
  if (address == "0.0.0.0" && index($0, probe) && port >= first && port < first + 160) { wildcard++; next }
  print } END { if (wildcard > 2) print "more than two wildcard sockets" }')
if [ -n "$sockets" ] && [ -z "$outside" ]; then
  pass "UDP sockets bound to 127.0.0.0/8, except Cyclone's two unicast receive ports ($(echo "$sockets" | wc -l) sockets)"
else
  fail "UDP sockets outside loopback (or none seen):"
  echo "$sockets"
fi
timeout 40 tail -s 0.05 --pid="$probe_pid" -f /dev/null
wait "$probe_pid"
rc=$?
cat "$work/cyclone_summary.json"
[ "$rc" -eq 0 ] && pass "the Cyclone DDS probe decoded every topic and its checks held" ||
  { fail "panoptes_cyclone_probe exit $rc"; tail -20 "$work/cyclone.log"; }
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null
expect_clean_exit "$estimator" "the live estimator" "$work/estimator.log"

summary="$work/cyclone_summary.json"
jq -e . "$summary" >/dev/null 2>&1 || { fail "the probe's summary is not JSON"; finish; }
# Most frames reach the Cyclone reader (best effort on loopback): at least 95% of the poses the
# estimator wrote during the probe's capture.
own=$(grep -c '"body"' "$work/own_poses.jsonl" || true)
decoded=$(jq '.native.bodies.samples' "$summary")
echo "poses: estimator wrote $own, Cyclone decoded $decoded from rt/panoptes/bodies"
[ "$decoded" -ge $((own * 95 / 100)) ] && pass "Cyclone decoded >= 95% of the poses ($decoded of $own)" ||
  fail "Cyclone decoded $decoded of $own poses"
# What Cyclone decoded is what the estimator wrote: the same doubles for the same body and stamp.
jq -c '[.stamp_ns, .body, .p, .q, .v, .w]' "$work/own_poses.jsonl" | sort >"$work/own_poses.keys"
jq -c '[.stamp_ns, .body, .p, .q, .v, .w]' "$work/cyclone/native_poses.jsonl" | sort >"$work/cyclone_poses.keys"
differing=$(comm -13 "$work/own_poses.keys" "$work/cyclone_poses.keys" | wc -l)
[ "$differing" -eq 0 ] && pass "every pose Cyclone decoded equals the estimator's own output, bit for bit" ||
  { fail "$differing poses Cyclone decoded differ from the estimator's own output"; comm -13 "$work/own_poses.keys" "$work/cyclone_poses.keys" | head -3; }
own_frames=$(jq -s 'map(.stamp_ns) | unique | length' "$work/own_tracks.jsonl")
decoded_frames=$(jq -s 'map(.stamp_ns) | unique | length' "$work/cyclone/native_tracks.jsonl")
[ "$decoded_frames" -ge $((own_frames * 95 / 100)) ] &&
  pass "Cyclone decoded >= 95% of the track frames ($decoded_frames of $own_frames stamps)" ||
  fail "Cyclone decoded $decoded_frames of $own_frames track frames"

# --- accuracy against the simulator's truth: Cyclone's copy scores as the estimator's own --------
# The estimator's own output of this run sets the bar, with margins for the few samples a
# best-effort reader may miss: pose RMSE +0.05 mm / +0.02 deg, tracked fraction -2%, no wrong pose;
# marker RMSE +0.1 mm, coverage -1%, no more ID switches.
evaluate() {  # evaluate NAME --poses|--tracks FILE [requirements...]: summary in $work/NAME.json
  local name="$1"
  shift
  "$bin/panoptes_eval" --scene "$scene" --epoch-ns "$epoch" --warmup 2 "$@" --summary-json "$work/$name.json" \
    >"$work/$name.out" 2>&1
  local rc=$?
  cat "$work/$name.out"
  return $rc
}
evaluate own_poses --poses "$work/own_poses.jsonl" || fail "panoptes_eval of the estimator's own poses"
evaluate own_tracks --tracks "$work/own_tracks.jsonl" || fail "panoptes_eval of the estimator's own tracks"
pose_mm=$(jq '[.bodies[].rmse_mm] | max + 0.05 | . * 1000 | round / 1000' "$work/own_poses.json")
pose_deg=$(jq '[.bodies[].rmse_deg] | max + 0.02 | . * 10000 | round / 10000' "$work/own_poses.json")
pose_tracked=$(jq '[.bodies[].tracked] | min - 0.02 | if . < 0 then 0 else . end | . * 1000 | floor / 1000' "$work/own_poses.json")
marker_mm=$(jq '.worst_marker_rmse_mm + 0.1 | . * 1000 | round / 1000' "$work/own_tracks.json")
coverage=$(jq '.coverage - 0.01 | . * 1000 | floor / 1000' "$work/own_tracks.json")
switches=$(jq '.id_switches' "$work/own_tracks.json")
pose_bar=(--require-pose-rmse-mm "$pose_mm" --require-pose-rmse-deg "$pose_deg" --require-pose-tracked "$pose_tracked"
  --require-no-wrong-poses)
evaluate cyclone_poses --poses "$work/cyclone/native_poses.jsonl" "${pose_bar[@]}" &&
  pass "rt/panoptes/bodies via Cyclone: pose RMSE <= $pose_mm mm, <= $pose_deg deg, tracked >= $pose_tracked" ||
  fail "rt/panoptes/bodies via Cyclone is less accurate than the estimator's own output"
evaluate cyclone_tracks --tracks "$work/cyclone/native_tracks.jsonl" --require-rmse-mm "$marker_mm" \
  --require-coverage "$coverage" --require-max-id-switches "$switches" &&
  pass "rt/panoptes/tracks via Cyclone: marker RMSE <= $marker_mm mm, coverage >= $coverage, <= $switches ID switches" ||
  fail "rt/panoptes/tracks via Cyclone is less accurate than the estimator's own output"

# --- ROS 2 topics --------------------------------------------------------------------------------
if [ ${#ros2_flag[@]} -gt 0 ]; then
  jq -e '.ros2_checked' "$summary" >/dev/null && pass "the ROS 2 topics were read" || fail "the ROS 2 topics were not read"
  evaluate ros2_poses --poses "$work/cyclone/ros2_poses.jsonl" "${pose_bar[@]}" &&
    pass "rt/panoptes/<body>/pose via Cyclone: as accurate as the estimator's own poses" ||
    fail "rt/panoptes/<body>/pose via Cyclone is less accurate than the estimator's own output"
  for body in head tool; do
    best=$(jq ".ros2.pose.$body.best_effort" "$summary")
    reliable=$(jq ".ros2.pose.$body.reliable" "$summary")
    written=$(grep -c "\"body\":\"$body\"" "$work/own_poses.jsonl" || true)
    [ "$best" -ge $((written * 95 / 100)) ] && [ "$reliable" -ge $((written * 95 / 100)) ] &&
      pass "rt/panoptes/$body/pose: best-effort $best and reliable $reliable samples (>= 95% of $written poses)" ||
      fail "rt/panoptes/$body/pose: best-effort $best, reliable $reliable of $written poses"
  done
  for topic in twist tf.transforms rigid_bodies.messages markers.messages; do
    count=$(jq ".ros2.$topic" "$summary")
    [ "$count" -gt 0 ] && pass "ros2 $topic: $count decoded" || fail "ros2 $topic: nothing decoded"
  done
  jq -c '.ros2.agreement' "$summary"
else
  echo "SKIP: ROS 2 topics (PANOPTES_CYCLONE_ROS2=0)"
fi
finish
