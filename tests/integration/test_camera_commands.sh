#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Every camera_command sent over DDS to a running camera_node (loopback profile), checked against
# the features it publishes: a command governs the frame right after it is applied. Also status,
# preview, predictions (guided search) and rejected commands.
source "$(dirname "$0")/lib.sh"

ctl() { "$bin/panoptes_ctl" "$@" --timeout 10; }
scene="$source_dir/deploy/scenes/demo.yaml"
"$bin/camera_node" --source "sim:$scene#cam0" --duration 19 --out-features "$work/features.jsonl" \
  >"$work/node.out" 2>"$work/node.err" &
node=$!
pids+=("$node")

ctl status --camera cam0 --count 1 >"$work/status0.json" && pass "status received" || fail "no status"
grep -q '"fps"' "$work/status0.json" && grep -q '"detect_p99_ms"' "$work/status0.json" && grep -q '"threshold":64' "$work/status0.json" \
  && pass "status carries fps, detection p99 and the default threshold" || fail "status fields: $(cat "$work/status0.json")"

cat >"$work/commands.txt" <<'COMMANDS'
cam0 set_threshold 255   # no 8-bit pixel can exceed it
sleep 0.5
cam0 set_threshold 0     # back to the default
sleep 0.3
* add_mask rect 0 0 640 480
sleep 0.5
cam0 clear_masks
sleep 0.3
cam0 capture_background 2
sleep 0.3
cam0 clear_background
other set_threshold 255  # addressed to another camera: ignored
cam0 set_exposure 500    # the simulator has no exposure control: rejected
cam0 set_gain 6          # nor gain
cam0 set_frame_rate 90   # nor a settable frame rate
cam0 set_threshold abc
cam0 no_such_command
sleep 0.2
cam0 restart
COMMANDS
ctl script "$work/commands.txt" >"$work/script.out" && pass "command script sent" || fail "command script"
# A command to one camera is written in that camera's DDS partition, a command to '*' in '*'.
grep -q '^sent set_threshold to cam0 (.*, partition cam0)$' "$work/script.out" &&
  grep -q '^sent add_mask to \* (.*, partition \*)$' "$work/script.out" &&
  pass "the script writes each camera's commands in its partition" || fail "script partitions: $(cat "$work/script.out")"
ctl preview cam0 --out "$work/preview.pgm" --width 160 >/dev/null && pass "preview received" || fail "no preview"
[ "$(head -c 2 "$work/preview.pgm" 2>/dev/null)" = "P5" ] && head -2 "$work/preview.pgm" | tail -1 | grep -q "160 120" \
  && pass "preview is a 160x120 PGM" || fail "preview file wrong"
# A prediction window around the whole frame: the node must switch to the guided search.
ctl predict cam0 --window 320 240 400 300 --duration 1.5 --rate 200 >/dev/null
sleep 1.2
ctl status --camera cam0 --count 1 >"$work/status1.json"
guided=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["counters"].get("guided_frames", 0))' "$work/status1.json" 2>/dev/null || echo 0)
[ "${guided:-0}" -gt 10 ] && pass "fresh predictions switch to the guided search ($guided frames)" || fail "guided frames: $guided"
grep -q '"last_error":"unknown command' "$work/status1.json" \
  && pass "status reports the last rejected command" || fail "status last_error: $(cat "$work/status1.json")"

kill -INT "$node"; wait "$node"; rc=$?
[ "$rc" -eq 0 ] && pass "node stopped cleanly" || fail "node exit $rc"

python3 - "$work/features.jsonl" "$work/node.err" <<'PY' && pass "each command governed the frame right after it was applied" || fail "command timing"
import json, re, sys
frames = {}
for line in open(sys.argv[1]):
    record = json.loads(line)
    frames[record["frame"]] = len(record["blobs"])
log = open(sys.argv[2]).read()
applied = [(m.group(1), " ".join(m.group(0).split()[:0]), int(m.group(2))) for m in
           re.finditer(r"command (\w+) #\d+ applied from frame (\d+)", log)]
def at(name, nth=0):
    hits = [frame for command, _, frame in applied if command == name]
    return hits[nth]
# The recorded frames nearest a command's first frame (under load the node's queue overwrites
# frames, so frame k - 1 or k itself may be missing from the record: the check then takes the
# nearest recorded one on that side).
def before(k):
    return frames.get(max((f for f in frames if f < k), default=-1), 0)
def from_(k):
    return frames.get(min((f for f in frames if f >= k), default=-1), 0)
ok = True
def check(condition, message):
    global ok
    if not condition:
        print("  FAILED:", message); ok = False
# set_threshold 255 (no pixel can exceed it) from frame a until set_threshold 0 from frame b.
a, b = at("set_threshold", 0), at("set_threshold", 1)
check(before(a) > 0, f"the last frame before {a} (set_threshold 255) had blobs")
check(all(frames.get(k, 0) == 0 for k in range(a, b) if k in frames), f"frames {a}..{b-1} have no blobs")
check(from_(b) > 0, f"from frame {b} (set_threshold 0) blobs again")
m, c = at("add_mask"), at("clear_masks")
check(before(m) > 0 and all(frames.get(k, 0) == 0 for k in range(m, c) if k in frames) and from_(c) > 0,
      f"mask over the whole frame from {m} to {c}")
for name in ("capture_background", "clear_background", "restart", "preview"):
    check(any(command == name for command, _, _ in applied), f"{name} applied")
check("set_exposure: exposure is not supported by the sim source" in log, "set_exposure rejected with a reason")
check("set_gain: gain is not supported by the sim source" in log, "set_gain rejected with a reason")
check("set_frame_rate: frame rate is not supported by the sim source" in log, "set_frame_rate rejected with a reason")
check("set_threshold: <T_a> 'abc' is not a number" in log, "bad argument rejected")
check("unknown command 'no_such_command'" in log, "unknown command rejected")
check(len([1 for command, _, _ in applied if command == "set_threshold"]) == 2, "the command for 'other' was ignored")
check(re.search(r"source counters: .*bad_command=5", log) is not None, "5 bad commands counted")
sys.exit(0 if ok else 1)
PY
grep -E "command|counters" "$work/node.err" | head -20
finish
