#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `estimator_node calibrate capture` live (issue 6): six camera_nodes replay simulated wand
# features over DDS (loopback profile) on a common epoch; the capture must record every camera's
# frames, close to all that were sent, and `calibrate solve` must succeed on the recording.
# Then, as root with nftables, the same inside a network namespace of its own over UDP only, with
# 10% of all datagrams dropped: the capture reads reliably, so lost frames are resent and it still
# records every frame.
source "$(dirname "$0")/lib.sh"
en="$bin/estimator_node"
# A DDS domain of its own (lib.sh): benchmarks and other tests on this machine publish cam0.. too
# (found: a latency benchmark's cameras doubled cam0-cam3 in the recording).

cp "$source_dir/deploy/scenes/wand_room.yaml" "$work/room.yaml"
expect_exit 0 "simulate wand features" -- "$bin/panoptes_sim" features --scene "$work/room.yaml" --out-dir "$work/wand" --duration 6
cameras=(cam0 cam1 cam2 cam3 cam4 cam5)

# capture TAG LEAD TAIL [PREFIX...]: the capture starts first (it also serves the time base) and
# outlasts the replay, which starts LEAD seconds later, by TAIL seconds (LEAD + 6 + TAIL in all, the
# scene being 6 s); every process runs under PREFIX (e.g. ip netns exec NAME). Checks that every
# camera was recorded with (nearly) every frame it published (camera_node's own count: under load
# it may drop frames in its detection queue before publishing, which is not the capture's doing).
capture() {
  local tag="$1" lead="$2" tail_s="$3" camera recorded sent got
  shift 3
  local epoch=$(( ($(date +%s) + lead) * 1000000000 ))
  "$@" "$en" calibrate capture --out "$work/capture_$tag.jsonl" --duration $((lead + 6 + tail_s)) --time-service \
    >"$work/capture_$tag.out" 2>"$work/capture_$tag.err" &
  local capture=$!
  pids+=("$capture")
  for camera in "${cameras[@]}"; do
    "$@" "$bin/camera_node" --source "features:$work/wand/$camera.jsonl" --sim-epoch-ns "$epoch" --duration $((lead + 8)) \
      --quiet >"$work/${camera}_$tag.log" 2>&1 &
    pids+=("$!")
  done
  timeout 30 tail -s 0.05 --pid="$capture" -f /dev/null
  wait "$capture"
  local rc=$?
  [ "$rc" -eq 0 ] && pass "$tag: calibrate capture exited cleanly" ||
    { fail "$tag: calibrate capture exit $rc"; tail -5 "$work/capture_$tag.err"; }
  cat "$work/capture_$tag.out"
  tail -2 "$work/capture_$tag.err"
  for camera in "${cameras[@]}"; do
    recorded=$(grep -c . "$work/wand/$camera.jsonl")
    sent=$(sed -n 's/.*stopped after \([0-9]*\) frames.*/\1/p' "$work/${camera}_$tag.log")
    got=$(grep -c "\"camera_id\":\"$camera\"" "$work/capture_$tag.jsonl" || true)
    echo "$tag $camera: $recorded in the file, published ${sent:-?}, captured $got"
    [ "${sent:-0}" -ge $(( recorded * 3 / 4 )) ] || fail "$tag: $camera published only ${sent:-no} of $recorded frames"
    if [ "$got" -ge $(( ${sent:-1} * 995 / 1000 )) ] && [ "$got" -le "${sent:-0}" ]; then
      pass "$tag: $camera: $got of $sent frames captured"
    else
      fail "$tag: $camera: $got of $sent frames captured"
    fi
  done
  grep -q "from 6 cameras" "$work/capture_$tag.out" && pass "$tag: the summary counts 6 cameras" ||
    fail "$tag: summary lacks 6 cameras"
}

# 2 s after the scene (4 s until issue 31): over shared memory nothing is lost, so nothing is
# resent after the last frame.
capture loopback 4 2
cp "$work/capture_loopback.jsonl" "$work/capture.jsonl"

# The recording solves.
expect_exit 0 "calibrate solve on the captured file" -- "$en" calibrate solve --cameras "$work/wand/calibration.yaml" \
  --in-features "$work/capture.jsonl" --wand 0,0.18,0.5 --out "$work/cal.yaml" --time-offsets
head -12 "$work/last.out"
grep -q "calibrated 6 of 6 cameras" "$work/last.out" && pass "all 6 cameras calibrated from the capture" ||
  fail "not all cameras calibrated from the capture"

# 10% loss: a namespace of our own, its loopback only, UDP only (shared memory would bypass the
# loss), and an nft rule dropping one UDP datagram in ten at random.
if [ "$(id -u)" -ne 0 ] || ! command -v nft >/dev/null; then
  echo "SKIP: the lossy capture needs root and nft"
  finish
fi
ns="panoptes_capture_$$"
ip netns add "$ns" || { fail "cannot create network namespace $ns"; finish; }
trap 'ip netns del "$ns" 2>/dev/null; cleanup' EXIT
ip -n "$ns" link set lo up
ip netns exec "$ns" nft -f - <<'NFT' || fail "cannot install the nft loss rule"
table inet lossy {
  chain in { type filter hook input priority 0; meta l4proto udp numgen random mod 10 0 counter drop; }
}
NFT
sed '/^          <transport_id>panoptes_shm<\/transport_id>/d' "$source_dir/deploy/dds/loopback.xml" >"$work/udp_only.xml"
# Lead 12 s, not 4 or 8: endpoint discovery (SEDP) crosses the same lossy link, and a lost
# announcement is repaired only at the next discovery heartbeat, seconds later. Once, with 4 s,
# cam3's writer and the capture matched 0.75 s after the epoch: its first 75 frames were gone before
# the match (issue 37; the 525 frames it did get were contiguous, "0 missing"). Once with 8 s (a
# fresh-clone suite at stop 99, beside the rest of the suite): cam3 matched 0.7 s after the epoch
# (530 of 600, "0 missing"); its clock sync had taken 2.25 s (0.25 s for cam0), 53 of its 103
# requests unanswered while its endpoints were not yet matched.
# 4 s after the scene: the last frames' lost datagrams are resent after the writer's next
# heartbeat (Fast DDS's default period is 3 s; deploy/dds/loopback.xml does not change it).
PANOPTES_DDS_PROFILE="$work/udp_only.xml" capture lossy 12 4 ip netns exec "$ns"
dropped=$(ip netns exec "$ns" nft list table inet lossy | grep -o "packets [0-9]*" | awk '{s += $2} END {print s + 0}')
[ "${dropped:-0}" -gt 200 ] && pass "lossy: $dropped UDP datagrams dropped, the capture still recorded every frame" ||
  fail "lossy: only ${dropped:-0} datagrams dropped"
grep -q "missing" "$work/capture_lossy.out" && grep "missing" "$work/capture_lossy.out" | head -6
ip netns del "$ns"
finish
