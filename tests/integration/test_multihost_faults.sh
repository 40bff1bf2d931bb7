#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Faults a real lab has, across namespace hosts (netns.sh) with the LAN profile: 4 camera hosts,
# an estimator host and an application host recording the TrackFrames it receives. One 34 s run:
#   t=5 s   camera 1's node is killed (-9), restarted at t=6 s  -> rejoins within 2 s, others go on
#   t=10 s  camera 2's cable is pulled for 5 s                  -> rejoins by itself
#   t=20 s  estimator_node is killed (-9) and restarted         -> tracks resume within 2 s
#   always  camera 3's link loses 10% and jitters by 20 ms      -> tracking continues
# The lossy link is `tc netem` on the host's eth0 when the kernel has sch_netem. Otherwise the loss
# is real all the same: nftables on host 4 drops 10% of the UDP datagrams it sends and receives
# (`numgen random`), and only the jitter is emulated by the sender (camera_node --inject-jitter-ms:
# without netem no qdisc delays packets). Without nft either, the camera node emulates both
# (--inject-loss). The log says which.
# Recovery times are measured from the application's records (receive times of TrackFrames).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/lib.sh"
source "$here/netns.sh"
netns_test_start

estimator_host=5
app_host=6
profile="$source_dir/deploy/dds/lan.xml"
netns_create_lan 6 || { fail "could not create the namespaces"; finish; }
scene="$work/scene.yaml"
# 25 s of the scene (27 s until issue 31): the faults at 4-17 s as before, and 4 s judged for
# accuracy after the restarted estimator's 4 s warm-up (about 900 instants, 1340 with 6 s; the
# bounds are RMSE < 2 mm and >= 95 % tracked, measured 1.4 mm and 100 %).
sed 's/^duration: .*/duration: 25.0/' "$source_dir/deploy/scenes/demo.yaml" >"$scene"
"$bin/panoptes_sim" calibration --scene "$scene" --out "$work/calibration.yaml" >/dev/null

now_ns() { date +%s%N; }
epoch=$(($(date +%s%N) + 3000000000))  # 3 s ahead (a whole second 3-4 s ahead until stop 71)
# sleep_until T: until scene time T seconds.
sleep_until() { sleep "$(python3 -c "import time; print(max(0.0, ($epoch + $1 * 1e9 - time.time_ns()) / 1e9))")"; }

start_estimator() {
  netns_spawn "$estimator_host" "$bin/estimator_node" --calibration "$work/calibration.yaml" \
    --dds-profile "$profile" --out-tracks "$work/tracks_$1.jsonl" --duration "$2" >"$work/estimator_$1.log" 2>&1 &
  estimator=$!
  pids+=("$estimator")
}
declare -A camera_pid=()
start_camera() {  # start_camera INDEX TAG [extra args]
  local i="$1" tag="$2"
  shift 2
  netns_spawn "$((i + 1))" "$bin/camera_node" --source "sim:$scene#cam$i" --sim-epoch-ns "$epoch" \
    --dds-profile "$profile" --quiet "$@" >"$work/cam${i}_$tag.log" 2>&1 &
  camera_pid[$i]=$!
  pids+=("$!")
}

# The lossy link of camera 3 (host 4).
lossy_args=()
nft_loss=0
if netns_exec 4 tc qdisc add dev eth0 root netem loss 10% delay 20ms 20ms 2>"$work/netem.err"; then
  lossy="tc netem on host 4's eth0 (loss 10%, delay 20 ms ± 20 ms)"
elif command -v nft >/dev/null && netns_exec 4 nft -f - 2>"$work/nft.err" <<'NFT'
table inet lossy {
  chain in { type filter hook input priority 0; meta l4proto udp numgen random mod 10 0 counter drop; }
  chain out { type filter hook output priority 0; meta l4proto udp numgen random mod 10 0 counter drop; }
}
NFT
then
  nft_loss=1
  lossy_args=(--inject-jitter-ms 20)
  lossy="nftables on host 4 (10% of UDP datagrams dropped each way) and the sender's jitter (--inject-jitter-ms 20; no sch_netem: $(head -1 "$work/netem.err"))"
else
  lossy_args=(--inject-loss 0.1 --inject-jitter-ms 20)
  lossy="the sender (camera_node --inject-loss 0.1 --inject-jitter-ms 20: no sch_netem, no nft)"
fi
echo "lossy link: $lossy"

start_estimator 1 24
netns_spawn "$app_host" "$bin/panoptes_track_probe" --dds-profile "$profile" --out "$work/probe.jsonl" \
  --duration 31 >"$work/probe.log" 2>&1 &
probe=$!
pids+=("$probe")
start_camera 0 a
start_camera 1 a
start_camera 2 a
start_camera 3 a "${lossy_args[@]}"

sleep_until 4
t_kill_camera=$(now_ns)
kill -KILL "${camera_pid[1]}"
wait "${camera_pid[1]}" 2>/dev/null || true
kill -0 "${camera_pid[1]}" 2>/dev/null && fail "camera_node cam1 survived kill -9"
sleep_until 5
t_restart_camera=$(now_ns)
start_camera 1 b

sleep_until 8
t_link_down=$(now_ns)
netns_link 3 down
sleep_until 13
t_link_up=$(now_ns)
netns_link 3 up

sleep_until 17
t_kill_estimator=$(now_ns)
kill -KILL "$estimator"
wait "$estimator" 2>/dev/null || true
t_restart_estimator=$(now_ns)
start_estimator 2 11  # until 3 s after the scene ends

for i in 0 1 2 3; do
  if timeout 25 tail -s 0.05 --pid="${camera_pid[$i]}" -f /dev/null && wait "${camera_pid[$i]}"; then
    pass "camera_node cam$i ran through to the end of the scene and exited cleanly"
  else
    fail "camera_node cam$i did not end cleanly"; tail -5 "$work"/cam${i}_*.log
  fi
done
# The scene is over: SIGINT ends the estimator and then the probe as their --duration would (the
# same summaries), ~3 s sooner, once the last frames have had 0.5 s to arrive.
sleep 0.5
kill -INT "$estimator" 2>/dev/null || true
timeout 20 tail -s 0.05 --pid="$estimator" -f /dev/null || true
wait "$estimator" && pass "the restarted estimator_node exited cleanly" || fail "restarted estimator_node"
sleep 0.3
kill -INT "$probe" 2>/dev/null || true
timeout 20 tail -s 0.05 --pid="$probe" -f /dev/null || true

python3 - "$work/probe.jsonl" "$t_kill_camera" "$t_restart_camera" "$t_link_down" "$t_link_up" \
  "$t_kill_estimator" "$t_restart_estimator" >"$work/recovery.txt" <<'PY'
import json, sys
records = [json.loads(l) for l in open(sys.argv[1])]
frames = [r for r in records if r["type"] == "tracks"]
kill_cam, restart_cam, link_down, link_up, kill_est, restart_est = map(int, sys.argv[2:8])
def first_after(t, pred):
    return min((r["recv_ns"] for r in frames if r["recv_ns"] > t and pred(r)), default=None)
def max_gap(t0, t1, pred):
    times = [t0] + sorted(r["recv_ns"] for r in frames if t0 <= r["recv_ns"] <= t1 and pred(r)) + [t1]
    return max(b - a for a, b in zip(times, times[1:])) / 1e9
full = lambda r: r["confirmed"] >= 3
out = {}
t = first_after(restart_cam, lambda r: r["camera"] == "cam1")
out["camera_rejoin_s"] = (t - restart_cam) / 1e9 if t else 99
out["camera_outage_gap_s"] = max_gap(kill_cam, restart_cam, full)
t = first_after(link_up, lambda r: r["camera"] == "cam2")
out["link_rejoin_s"] = (t - link_up) / 1e9 if t else 99
out["link_outage_gap_s"] = max_gap(link_down, link_up, full)
t = first_after(restart_est, full)
out["estimator_resume_s"] = (t - restart_est) / 1e9 if t else 99
out["estimator_outage_s"] = (t - kill_est) / 1e9 if t else 99
print(json.dumps(out))
PY
cat "$work/recovery.txt"
value() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$work/recovery.txt" "$1"; }
check_le() {  # check_le KEY LIMIT DESCRIPTION
  local v
  v=$(value "$1")
  if python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) <= float(sys.argv[2]) else 1)" "$v" "$2"; then
    pass "$3: $v s (limit $2 s)"
  else
    fail "$3: $v s (limit $2 s)"
  fi
}
check_le camera_rejoin_s 2.0 "killed camera node restarted: its frames drive tracks again after"
check_le camera_outage_gap_s 0.25 "while it was down the other cameras kept 3 tracks; longest gap"
check_le link_rejoin_s 5.0 "cable back in: the camera rejoined by itself after"
check_le link_outage_gap_s 0.25 "while the cable was out the others kept 3 tracks; longest gap"
check_le estimator_resume_s 2.0 "estimator restarted: 3 confirmed tracks again after"

# The restarted estimator reloaded its calibration and tracks accurately from 4 s after restart to
# the end, with camera 3 on the lossy link throughout.
if "$bin/panoptes_eval" --scene "$scene" --tracks "$work/tracks_2.jsonl" --epoch-ns "$epoch" --warmup 21 \
  --require-rmse-mm 2 --require-tracked 0.95 >"$work/eval.txt" 2>&1; then
  pass "after the restart, with the lossy link: RMSE < 2 mm, >= 95% tracked ($(grep '^all:' "$work/eval.txt"))"
else
  fail "accuracy after the restart with the lossy link"; cat "$work/eval.txt"
fi
usage=$(grep -h "camera cam3: .*utilisation" "$work/estimator_2.log" || true)
echo "$usage"
echo "$usage" | awk '{for (i = 1; i < NF; ++i) { if ($i == "frames") f = $(i + 1); if ($i == "utilisation") u = $(i + 1) }}
  END {exit !(u >= 0.95 && f > 0)}' && pass "lossy camera: every frame that arrived was used (late ones replayed)" ||
  fail "lossy camera utilisation: $usage"
if [ "$nft_loss" = 1 ]; then
  dropped=$(netns_exec 4 nft list table inet lossy | grep -o "packets [0-9]*" | awk '{s += $2} END {print s + 0}')
  [ "${dropped:-0}" -gt 100 ] && pass "host 4's link dropped $dropped UDP datagrams" || fail "host 4 dropped only ${dropped:-0} datagrams"
elif [[ " ${lossy_args[*]} " == *" --inject-loss "* ]]; then
  lost=$(grep -o "injected_losses=[0-9]*" "$work/cam3_a.log" | tail -1 | cut -d= -f2 || true)
  [ "${lost:-0}" -gt 100 ] && pass "sender-side loss injected ($lost frames)" || fail "no injected losses counted"
fi
netns_cleanup
[ "$(ip netns list | grep -c "^$netns_prefix" || true)" -eq 0 ] && pass "every namespace deleted" || fail "namespaces left"
finish
