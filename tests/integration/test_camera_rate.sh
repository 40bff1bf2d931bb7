#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A 2048x1088 stream at 500 Hz from the simulator through camera_node over DDS: sustained rate,
# drops and detection p99 from the node's own status (docs/benchmarks.md). Prints one JSON line
# with the figures; fails below 80% of the frames (the renderer shares the two cores).
source "$(dirname "$0")/lib.sh"

seconds=${PANOPTES_RATE_SECONDS:-8}
"$bin/camera_node" --source "sim:$source_dir/deploy/scenes/rate500.yaml#fast0" --duration $((seconds + 2)) \
  --queue-capacity 16 >"$work/node.out" 2>"$work/node.err" &
node=$!
pids+=("$node")
"$bin/panoptes_ctl" status --camera fast0 --count "$seconds" --timeout $((seconds + 8)) >"$work/status.jsonl"
wait "$node"
python3 - "$work/status.jsonl" "$seconds" <<'PY'
import json, sys
rows = [json.loads(line) for line in open(sys.argv[1])]
steady = rows[1:] or rows           # the first period includes start-up
fps = sum(r["fps"] for r in steady) / len(steady)
p99 = max(r["detect_p99_ms"] for r in steady)
p50 = sorted(r["detect_p50_ms"] for r in steady)[len(steady) // 2]
last = rows[-1]
overwritten = last["counters"].get("overwritten", 0)
print(json.dumps({"frame": "2048x1088_8bit", "rate_hz": 500, "sustained_fps": round(fps, 1),
                  "frames": last["frames"], "drops_queue": last["drops_queue"], "overwritten": overwritten,
                  "detect_p50_ms": round(p50, 4), "detect_p99_ms_worst_second": round(p99, 4)}))
sys.exit(0 if fps >= 400 else 1)
PY
[ $? -eq 0 ] && pass "camera_node sustained >= 80% of 500 Hz at 2048x1088" || fail "camera_node fell below 400 fps"
tail -2 "$work/node.err"
finish
