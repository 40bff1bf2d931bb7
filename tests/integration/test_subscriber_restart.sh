#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A FeatureFrame subscriber killed with SIGKILL and started again receives every camera's frames
# (docs/protocol.md, "Restarting after a crash"). Two simulated camera_nodes run; a
# panoptes_feature_probe is started, killed with -9 and started again five times, the last time
# after `fastdds shm clean`. Each restarted probe must see both cameras within 10 s, must not take
# the killed probe's shared-memory port while that port is a zombie (its segment and lock file
# left behind: Fast DDS 2.9 would remove the segment the cameras still write into) or after
# `fastdds shm clean` removed it under the cameras, and no camera may map the port it reads as a
# removed segment. tests/stress/subscriber_restart.sh does the same with the console, K times.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/console.yaml"
cameras=(cam0 cam1)
camera_pids=()
for camera in "${cameras[@]}"; do
  "$bin/camera_node" --source "sim:$scene#$camera" --duration 60 --quiet >"$work/$camera.log" 2>&1 &
  pids+=("$!")
  camera_pids+=("$!")
done

# own_shm_port PID: the shared-memory port a process reads (the one whose reader lock file it holds).
own_shm_port() {
  ls -l "/proc/$1/fd" 2>/dev/null | sed -n 's|.*/dev/shm/fastrtps_port\([0-9]*\)_el$|\1|p' | head -n 1
}

# sees_every_camera FILE: the probe's last line counts frames from every camera.
sees_every_camera() {
  [ -s "$1" ] && /usr/bin/python3 -c '
import json, sys
line = open(sys.argv[1]).read().strip().splitlines()[-1]
features = json.loads(line)["features"]
sys.exit(0 if all(features.get(c, 0) > 0 for c in sys.argv[2:]) else 1)' "$1" "${cameras[@]}" 2>/dev/null
}

# start_probe RUN: starts probe RUN (pid in $probe).
start_probe() {
  "$bin/panoptes_feature_probe" --out "$work/probe$1.jsonl" --period 0.1 >"$work/probe$1.log" 2>&1 &
  probe=$!
  pids+=("$probe")
}

# wait_every_camera RUN START_NS: waits (10 s at most) until probe RUN has seen every camera;
# prints the milliseconds since START_NS.
wait_every_camera() {
  local start=$2 elapsed
  while :; do
    elapsed=$(( ($(date +%s%N) - start) / 1000000 ))
    if sees_every_camera "$work/probe$1.jsonl"; then echo "$elapsed"; return 0; fi
    [ "$elapsed" -ge 10000 ] && return 1
    sleep 0.1
  done
}

sleep 1
start_ns=$(date +%s%N)
start_probe 0
if ms=$(wait_every_camera 0 "$start_ns"); then pass "the first probe sees cam0 and cam1 ($ms ms)"; else fail "the first probe did not see both cameras"; finish; fi
# camera_maps_removed PORT: the cameras that map shared-memory port PORT as a removed segment.
camera_maps_removed() {
  local i
  for i in "${!cameras[@]}"; do
    grep -q "fastrtps_port$1 (deleted)" "/proc/${camera_pids[$i]}/maps" 2>/dev/null && printf '%s ' "${cameras[$i]}"
  done
}

zombie_checks=0
cleaned_checks=0
for run in 1 2 3 4 5; do
  killed_port="$(own_shm_port "$probe")"
  kill -KILL "$probe"
  wait "$probe" 2>/dev/null
  # A zombie when the new probe starts, unless a camera already replaced the segment.
  zombie=0 cleaned=0
  [ -n "$killed_port" ] && [ -e "/dev/shm/fastrtps_port$killed_port" ] && [ -e "/dev/shm/fastrtps_port${killed_port}_el" ] && zombie=1
  if [ "$run" -eq 5 ] && command -v fastdds >/dev/null; then
    fastdds shm clean >/dev/null 2>&1
    zombie=0
    [ -n "$killed_port" ] && [ ! -e "/dev/shm/fastrtps_port$killed_port" ] && [ -n "$(camera_maps_removed "$killed_port")" ] && cleaned=1
  fi
  start_ns=$(date +%s%N)
  start_probe "$run"
  if ms=$(wait_every_camera "$run" "$start_ns"); then
    pass "restart $run: the probe sees cam0 and cam1 ($ms ms after its start)"
  else
    fail "restart $run: the probe did not see both cameras in 10 s: $(tail -n 1 "$work/probe$run.jsonl" 2>/dev/null)"
  fi
  new_port="$(own_shm_port "$probe")"
  if [ "$zombie" -eq 1 ] || [ "$cleaned" -eq 1 ]; then
    [ "$zombie" -eq 1 ] && what="zombie" && zombie_checks=$((zombie_checks + 1))
    [ "$cleaned" -eq 1 ] && what="removed (fastdds shm clean) but mapped" && cleaned_checks=$((cleaned_checks + 1))
    if [ -n "$new_port" ] && [ "$new_port" != "$killed_port" ]; then
      pass "restart $run: the new probe reads port $new_port, not the killed probe's $what port $killed_port"
    else
      fail "restart $run: the new probe took the killed probe's $what port $killed_port (reads '${new_port}')"
    fi
  fi
  orphaned="$(camera_maps_removed "$new_port")"
  [ -z "$orphaned" ] || fail "restart $run: $orphaned write into a removed segment of port $new_port, the one the probe reads"
done
[ "$zombie_checks" -gt 0 ] && pass "the killed probe's port was a zombie at $zombie_checks of 4 restarts" ||
  fail "the killed probe's port was never a zombie when the new probe started: nothing was checked"
if command -v fastdds >/dev/null; then
  [ "$cleaned_checks" -eq 1 ] && pass "after fastdds shm clean the cameras still mapped the killed probe's removed port" ||
    fail "after fastdds shm clean no camera mapped the killed probe's removed port: nothing was checked"
fi
finish
