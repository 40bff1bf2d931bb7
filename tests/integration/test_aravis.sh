#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The aravis source over the real GigE Vision protocol (GVCP control, GVSP stream): a fake camera
# serving synthetic IR frames with known spot positions, camera_node detecting them, and the
# source's behaviour under packet loss, a vanished camera and restart().
#
# GigE Vision discovery broadcasts on every interface, so the whole test re-executes itself inside
# a new network namespace whose only interface is lo: nothing it sends can leave it.
if [ -z "${PANOPTES_ARAVIS_NETNS:-}" ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "FAIL: test_aravis.sh must run as root: it creates a network namespace (unshare --net) to keep"
    echo "      GigE Vision traffic off the host's networks"
    exit 1
  fi
  if ! command -v unshare >/dev/null || ! command -v ip >/dev/null; then
    echo "FAIL: test_aravis.sh needs unshare (util-linux) and ip (iproute2) for its network namespace"
    exit 1
  fi
  PANOPTES_ARAVIS_NETNS=1 exec unshare --net -- bash "$0" "$@"
  echo "FAIL: unshare --net failed: cannot create a network namespace"
  exit 1
fi
if ! ip link set lo up; then
  echo "FAIL: cannot bring lo up inside the network namespace"
  exit 1
fi
if [ "$(ip -o link show | wc -l)" -ne 1 ]; then
  echo "FAIL: the namespace has interfaces other than lo:"; ip -o link show
  exit 1
fi

source "$(dirname "$0")/lib.sh"
checker="$source_dir/tests/tools/check_spot_truth.py"

# start_fake NAME ARGS... : starts panoptes_fake_gige in the background (output in $work/NAME.log)
# and waits until it serves; sets fake_pid.
start_fake() {
  local name="$1"
  shift
  "$bin/panoptes_fake_gige" "$@" >"$work/$name.log" 2>&1 &
  fake_pid=$!
  pids+=("$fake_pid")
  for _ in $(seq 50); do
    grep -q "serving" "$work/$name.log" && return 0
    kill -0 "$fake_pid" 2>/dev/null || break
    sleep 0.1
  done
  fail "fake camera $name did not start"; cat "$work/$name.log"
  return 1
}

stop_fake() {
  kill -INT "$fake_pid" 2>/dev/null
  for _ in $(seq 50); do kill -0 "$fake_pid" 2>/dev/null || return 0; sleep 0.1; done
  kill -KILL "$fake_pid" 2>/dev/null
}

# counter NAME FILE: the value of NAME on the "source counters:" line of FILE (0 if absent).
counter() {
  local value
  value=$(grep "source counters:" "$2" | tail -1 | tr ' ' '\n' | sed -n "s/^$1=//p")
  echo "${value:-0}"
}

# --- detection against the truth -----------------------------------------------------------------
start_fake clean --truth "$work/truth.jsonl" --rate 50 --noise 1 --seed 11 || finish
expect_exit 0 "camera_node reads 150 frames from the GigE Vision camera at 127.0.0.1" -- \
  timeout 60 "$bin/camera_node" --source aravis:127.0.0.1 --no-dds --out-features "$work/features.jsonl" \
  --max-frames 150 --quiet
cp "$work/last.err" "$work/clean.err"
stop_fake
# The fake's device clock is the wall clock; the source maps device stamps onto it through the
# lower envelope of arrival - stamp, so a stamp should be the device's plus the latency floor (the
# fake's render time, which the truth records) plus half the 10 ms exposure, to within about one
# frame's transfer. Over 3 s no drift is fitted, so the envelope is the smallest arrival - stamp so
# far and the error only shrinks: the stamps are judged over the last 75 frames. (Judged from frame
# 20, a fresh-clone run beside other tests failed once: every one of its first 20 frames arrived at
# least 2.7 ms late.)
if python3 "$checker" --truth "$work/truth.jsonl" --features "$work/features.jsonl" --min-frames 150 \
  --max-error-px 0.1 --min-detected 0.99 --max-stamp-error-ms 1.5 --stamp-warmup 75 >"$work/check.out" 2>&1; then
  pass "every spot found within 0.1 px, stamps of the last 75 frames within 1.5 ms: $(cat "$work/check.out")"
else
  fail "detections against the truth"; cat "$work/check.out"
fi
if grep -q "source counters:" "$work/clean.err"; then
  pass "camera_node prints its source counters at exit: $(grep "source counters:" "$work/clean.err")"
else
  fail "camera_node printed no 'source counters:' line"; cat "$work/clean.err"
fi

# --- errors a user gets ----------------------------------------------------------------------------
expect_exit 2 "no camera at the address" -- timeout 30 "$bin/camera_node" --source aravis:127.0.0.2 --no-dds \
  --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:127.0.0.2: no GigE Vision camera answered at 127.0.0.2" "the silent address is named"
[ "$(wc -l <"$work/last.err")" -eq 1 ] && pass "one-line reason" || fail "$(wc -l <"$work/last.err") lines of error"
expect_exit 2 "an address with no route" -- timeout 30 "$bin/camera_node" --source aravis:10.255.0.1 --no-dds \
  --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:10.255.0.1: no route to 10.255.0.1" "the unreachable address is named"

# --- GenICam timing features over GVCP ------------------------------------------------------------
# The fake serves Aravis's fake-camera description: triggers (rising edge only), no PTP, no lines.
# The writes and PTP stamps themselves are checked in-process (camera_tests GenicamTiming.*); here
# the refusals and a trigger configuration travel over the real control protocol.
start_fake timing --rate 50 --seed 12 || finish
expect_exit 2 "PTP on a GigE Vision camera without it" -- timeout 30 "$bin/camera_node" --source aravis:127.0.0.1 \
  --ptp on --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:127.0.0.1: ptp: the camera has neither PtpEnable nor GevIEEE1588" "camera and features named"
expect_exit 2 "a strobe on a GigE Vision camera without output lines" -- timeout 30 "$bin/camera_node" \
  --source aravis:127.0.0.1 --strobe Line1 --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:127.0.0.1: strobe Line1: the camera has no LineSelector feature" "camera and feature named"
# Triggered from Line0 the GigE Vision fake sends nothing (it sends free-running or on a software
# trigger only), like a real camera with no trigger pulses: stop the node after 3 s and look at
# what it read back at start.
timeout -s INT 3 "$bin/camera_node" --source aravis:127.0.0.1 --trigger Line0 --no-dds \
  --out-features "$work/x.jsonl" >/dev/null 2>"$work/trigger.err"
if grep -qF "TriggerSelector=FrameStart TriggerMode=On TriggerSource=Line0 TriggerActivation=RisingEdge" "$work/trigger.err"; then
  pass "a trigger is configured over GVCP and read back"
else
  fail "no trigger read-back line"; cat "$work/trigger.err"
fi
stop_fake

# --- packet loss -----------------------------------------------------------------------------------
# 2 per mille of the packets dropped: about a third of the 640x480 frames (220 packets) lose one.
start_fake lossy --truth "$work/truth_lossy.jsonl" --rate 50 --loss 0.002 --seed 12 || finish
expect_exit 0 "camera_node keeps running under packet loss" -- \
  timeout 60 "$bin/camera_node" --source aravis:127.0.0.1 --no-dds --out-features "$work/lossy.jsonl" \
  --max-frames 100 --quiet
cp "$work/last.err" "$work/lossy.err"
stop_fake
if python3 "$checker" --truth "$work/truth_lossy.jsonl" --features "$work/lossy.jsonl" --min-frames 100 \
  --max-error-px 0.1 --min-detected 0.99 >"$work/check_lossy.out" 2>&1; then
  pass "frames delivered under loss are whole: $(cat "$work/check_lossy.out")"
else
  fail "frames delivered under loss"; cat "$work/check_lossy.out"
fi
incomplete=$(counter incomplete "$work/lossy.err")
[ "$incomplete" -gt 0 ] && pass "incomplete frames counted, not delivered ($incomplete)" ||
  fail "no incomplete frames counted under loss: $(grep "source counters" "$work/lossy.err")"
gaps=$(python3 -c "import json,sys; f=[json.loads(l)['frame'] for l in open(sys.argv[1])]; print(sum(b-a-1 for a,b in zip(f,f[1:])))" "$work/lossy.jsonl")
[ "$gaps" -gt 0 ] && pass "frame numbers skip the $gaps undelivered frames" || fail "no gaps in frame numbers under loss"

# --- a camera that vanishes and comes back ----------------------------------------------------------
start_fake first --rate 50 --seed 13 || finish
"$bin/panoptes_source_probe" --source aravis:127.0.0.1 --frames 200 --timeout-ms 200 --reconnect-ms 200 \
  >"$work/probe.out" 2>"$work/probe.err" &
probe_pid=$!
pids+=("$probe_pid")
sleep 1.5
kill -KILL "$fake_pid"  # power cut: no goodbye on the control channel
sleep 1.5
start_fake second --rate 50 --seed 14 || finish
for _ in $(seq 300); do kill -0 "$probe_pid" 2>/dev/null || break; sleep 0.1; done
if kill -0 "$probe_pid" 2>/dev/null; then
  fail "the source did not recover within 30 s"; kill -INT "$probe_pid"
fi
wait "$probe_pid"
stop_fake
grep -q "read 200 frames" "$work/probe.err" && pass "all 200 frames read across the outage" ||
  { fail "frames across the outage"; cat "$work/probe.err"; }
[ "$(counter disconnect "$work/probe.err")" -ge 1 ] && pass "the outage is counted ($(counter disconnect "$work/probe.err") disconnect)" ||
  fail "no disconnect counted: $(cat "$work/probe.err")"
[ "$(counter reconnect "$work/probe.err")" -ge 1 ] && pass "the reconnection is counted" ||
  fail "no reconnect counted: $(cat "$work/probe.err")"

# --- restart() -------------------------------------------------------------------------------------
start_fake restart --rate 50 --seed 15 || finish
expect_exit 0 "restart() mid-stream" -- timeout 60 "$bin/panoptes_source_probe" --source aravis:127.0.0.1 \
  --frames 60 --restart-after 20
stop_fake
expect_stderr_contains "read 60 frames" "frames continue after restart()"
[ "$(counter restart "$work/last.err")" -eq 1 ] && [ "$(counter reconnect "$work/last.err")" -eq 1 ] &&
  pass "restart and reopen counted once each" || fail "restart counters: $(cat "$work/last.err")"
finish
