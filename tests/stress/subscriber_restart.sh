#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Stress (not in CI): does a subscriber killed with SIGKILL and started again see FeatureFrames from
# every camera? Starts the simulated cameras of deploy/scenes/console.yaml (camera_node --source
# sim:...), then starts the subscriber, kills it with -9 and starts it again K times. After each
# start it waits (bounded) until FeatureFrames from every camera have arrived and prints one line:
# the restart, the seconds until every camera was seen, the cameras still missing at the timeout and
# whether their CameraStatus arrived, and which cameras still map a removed shared-memory port. The
# last line is a JSON summary. Findings and figures: docs/protocol.md ("Restarting after a crash"),
# docs/protocol.md ("Subscriber restart after SIGKILL: measurements").
#
#   bash tests/stress/subscriber_restart.sh BUILD_DIR [options]
#     --restarts K        restarts (20)
#     --subscriber S      console (panoptes_console, read through /api/state) or probe
#                         (panoptes_feature_probe, one JSON line per second) (console)
#     --timeout S         seconds a started subscriber has to see every camera (10)
#     --gap S             seconds between the kill and the new start (0.3)
#     --with-estimator    also run estimator_node and panoptes_record --idle, as test_console.sh does
#     --profile FILE      DDS profile (deploy/dds/loopback.xml)
#     --keep              keep the work directory
# Traffic stays on this host (the loopback profile). Use a private domain: PANOPTES_DOMAIN=N.
set -uo pipefail
build_dir="$(cd "${1:?usage: subscriber_restart.sh BUILD_DIR [options]}" && pwd)"
shift
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
bin="$build_dir/bin"
restarts=20 subscriber=console timeout_s=10 gap_s=0.3 with_estimator=0 keep=0
profile="$source_dir/deploy/dds/loopback.xml"
while [ $# -gt 0 ]; do
  case "$1" in
    --restarts) restarts="$2"; shift 2 ;;
    --subscriber) subscriber="$2"; shift 2 ;;
    --timeout) timeout_s="$2"; shift 2 ;;
    --gap) gap_s="$2"; shift 2 ;;
    --with-estimator) with_estimator=1; shift ;;
    --profile) profile="$2"; shift 2 ;;
    --keep) keep=1; shift ;;
    *) echo "subscriber_restart.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
case "$subscriber" in console | probe) ;; *) echo "--subscriber: console or probe" >&2; exit 2 ;; esac
export PANOPTES_DDS_PROFILE="$profile"
cameras=(cam0 cam1 cam2 cam3)
work="$(mktemp -d /tmp/panoptes-restart-XXXXXX)"
pids=()
camera_pids=()
subscriber_pid=""

cleanup() {
  if [ -n "$subscriber_pid" ]; then
    kill -KILL "$subscriber_pid" 2>/dev/null
    wait "$subscriber_pid" 2>/dev/null
  fi
  for pid in "${pids[@]}"; do kill -INT "$pid" 2>/dev/null; done
  sleep 0.5
  for pid in "${pids[@]}"; do kill -KILL "$pid" 2>/dev/null; done
  wait 2>/dev/null
  bash "$source_dir/deploy/dds-shm-clean.sh"
  if [ "$keep" -eq 1 ]; then echo "kept $work" >&2; else rm -rf "$work"; fi
}
trap cleanup EXIT

# Long enough for every restart to time out.
duration=$(awk -v k="$restarts" -v t="$timeout_s" -v g="$gap_s" 'BEGIN { printf "%d", 30 + k * (t + g + 2) }')
# The console scene, lasting as long as the run.
sed "s/^duration: .*/duration: $duration.0/" "$source_dir/deploy/scenes/console.yaml" >"$work/scene.yaml"
scene="$work/scene.yaml"
if [ "$with_estimator" -eq 1 ]; then
  "$bin/panoptes_sim" calibration --scene "$scene" --out "$work/calibration.yaml" >/dev/null 2>&1 &&
    "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 0.1 >/dev/null 2>&1 ||
    { echo "cannot simulate $scene" >&2; exit 1; }
  "$bin/estimator_node" --calibration "$work/calibration.yaml" --bodies "$work/sim/bodies.yaml" \
    --status-period 1 --duration "$duration" >"$work/estimator.log" 2>&1 &
  pids+=("$!")
  "$bin/panoptes_record" --idle --id stress --out "$work/idle.mcap" --quiet >"$work/recorder.log" 2>&1 &
  pids+=("$!")
fi
for camera in "${cameras[@]}"; do
  "$bin/camera_node" --source "sim:$scene#$camera" --duration "$duration" --quiet >"$work/$camera.log" 2>&1 &
  pids+=("$!")
  camera_pids+=("$!")
done
token="restart-stress-$(head -c 8 /dev/urandom | od -An -tx1 | tr -d ' \n')"
echo "$token" >"$work/token"
port=""

start_subscriber() {  # RUN
  if [ "$subscriber" = console ]; then
    rm -f "$work/url"
    "$bin/panoptes_console" --bind "127.0.0.1:${port:-0}" --token-file "$work/token" --url-file "$work/url" \
      >"$work/subscriber$1.log" 2>&1 &
    subscriber_pid=$!
  else
    "$bin/panoptes_feature_probe" --out "$work/probe$1.jsonl" --period 0.2 >"$work/subscriber$1.log" 2>&1 &
    subscriber_pid=$!
  fi
}

# Prints "seen missing status_of_missing" for the subscriber's current view, nothing if not ready.
observe() {  # RUN
  local state
  if [ "$subscriber" = console ]; then
    [ -s "$work/url" ] || return 0
    if [ -z "$port" ]; then port="$(sed 's|http://127.0.0.1:\([0-9]*\)/.*|\1|' "$work/url")"; fi
    state="$(curl -s --max-time 1 "http://127.0.0.1:$port/api/state?token=$token")" || return 0
  else
    [ -s "$work/probe$1.jsonl" ] || return 0
    state="$(tail -n 1 "$work/probe$1.jsonl")"
  fi
  /usr/bin/python3 -c '
import json, sys
try:
    state = json.loads(sys.argv[1])
except ValueError:
    sys.exit(0)
wanted = sys.argv[2].split()
if "cameras" in state and isinstance(state["cameras"], list):  # the console
    cams = {c["id"]: (c.get("frame", 0) > 0, "status" in c) for c in state["cameras"]}
else:  # the probe: {"features": {id: n}, "status": {id: n}}
    cams = {i: (state["features"].get(i, 0) > 0, state["status"].get(i, 0) > 0) for i in wanted}
seen = [i for i in wanted if cams.get(i, (False, False))[0]]
missing = [i for i in wanted if i not in seen]
status = ",".join(i + (":status" if cams.get(i, (False, False))[1] else ":no-status") for i in missing)
print(len(seen), ",".join(missing) or "-", status or "-")
' "$state" "${cameras[*]}"
}

wait_all_cameras() {  # RUN -> "seconds missing status"
  local start now seen_line="" elapsed
  start=$(date +%s%N)
  while :; do
    now=$(date +%s%N)
    elapsed=$(( (now - start) / 1000000 ))
    seen_line="$(observe "$1")"
    if [ -n "$seen_line" ] && [ "${seen_line%% *}" -eq "${#cameras[@]}" ]; then
      awk -v ms="$elapsed" 'BEGIN { printf "%.2f - -\n", ms / 1000 }'
      return 0
    fi
    if [ "$elapsed" -ge $((timeout_s * 1000)) ]; then
      echo "timeout ${seen_line#* }"
      return 1
    fi
    sleep 0.1
  done
}

sleep 2  # the cameras join
start_subscriber 0
wait_all_cameras 0 >"$work/run0" || { echo "the first subscriber did not see every camera: $(cat "$work/run0")" >&2; }
echo "start 0: $(cat "$work/run0")"
failures=0
times=()
for run in $(seq 1 "$restarts"); do
  kill -KILL "$subscriber_pid"
  wait "$subscriber_pid" 2>/dev/null
  sleep "$gap_s"
  start_subscriber "$run"
  if result="$(wait_all_cameras "$run")"; then
    times+=("${result%% *}")
    echo "restart $run: every camera after ${result%% *} s"
  else
    failures=$((failures + 1))
    echo "restart $run: FAILED, missing after ${timeout_s} s: $(cut -d' ' -f3 <<<"$result")"
    [ "$subscriber" = probe ] && echo "  probe: $(tail -n 1 "$work/probe$run.jsonl" 2>/dev/null)"
    if [ "$subscriber" = console ]; then
      curl -s --max-time 1 "http://127.0.0.1:$port/api/stats?token=$token" >"$work/stats$run.json"
    fi
    ls -la /dev/shm >"$work/shm$run.txt"
    # Shared-memory ports a camera still maps although their file was removed (see docs/deployment.md).
    for i in "${!cameras[@]}"; do
      orphans="$(grep -o 'fastrtps_port[0-9]* (deleted)' "/proc/${camera_pids[$i]}/maps" 2>/dev/null | sort -u | tr '\n' ' ')"
      [ -n "$orphans" ] && echo "  ${cameras[$i]} maps removed ports: $orphans"
    done
    if [ "$keep" -eq 1 ] && [ "$failures" -eq 1 ]; then  # a second opinion on the first failure
      "$bin/panoptes_feature_probe" --out "$work/witness$run.jsonl" --period 0.5 --duration 4 >/dev/null 2>&1
      echo "  a probe started beside it: $(tail -n 1 "$work/witness$run.jsonl")"
    fi
  fi
done
# Shared-memory ports of this domain left at the end (each participant of the loopback profile has
# one for user data: Fast DDS's port 7411 + 250 * domain + 2 * participant id).
domain="${PANOPTES_DOMAIN:-0}"
first_port=$((7411 + 250 * domain))
ports_left=$(ls /dev/shm | sed -n 's/^fastrtps_port\([0-9]*\)$/\1/p' |
  awk -v lo="$first_port" '$1 >= lo && $1 < lo + 240' | wc -l)
summary="$(printf '%s\n' "${times[@]}" | sort -n | awk -v k="$restarts" -v f="$failures" -v s="$subscriber" -v p="$ports_left" '
  { t[NR] = $1 }
  END {
    p50 = NR ? t[int((NR + 1) / 2)] : -1; max = NR ? t[NR] : -1
    printf "{\"subscriber\": \"%s\", \"restarts\": %d, \"failures\": %d, \"p50_s\": %s, \"max_s\": %s, \"shm_ports\": %d}\n", s, k, f, p50, max, p
  }')"
echo "$summary"
[ "$failures" -eq 0 ]
