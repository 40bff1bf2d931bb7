#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Surface mode (LumiPoint, issue 22, docs/surface.md) through real processes: the surface_wall
# scene (a 3 x 1 m wall, three cameras with overlapping views, five laser spots switched on and off)
# simulated, replayed by three camera_nodes into estimator_node --surface, and read by the
# lumipoint_board example on the client library. Checks: every true stroke (a run of pen-down
# time) is one stroke with one begin and one end near the truth's times, none split, merged or
# duplicated where the cameras overlap; the board's image shows each stroke's colour along the
# true path and nothing elsewhere; the offline mode gives the same strokes; bad surface settings
# exit 2 naming the file and key.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/surface_wall.yaml"
surface="$source_dir/deploy/scenes/surface_wall_surface.yaml"
# The live run's settings (benchmark aid: another latency_window_ms, docs/surface.md, "End-to-end
# stroke latency").
live_surface="${PANOPTES_SURFACE_LIVE_SETTINGS:-$surface}"
for tool in lumipoint_board estimator_node camera_node panoptes_sim panoptes_track_probe; do
  [ -x "$bin/$tool" ] || { fail "$bin/$tool is not built"; finish; }
done

# --- bad input: exit 2 naming the file and key ----------------------------------------------------
expect_exit 0 "simulate the surface_wall scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
cal="$work/sim/calibration.yaml"
cat >"$work/degenerate.yaml" <<YAML
surface:
  size: [3.0, 1.0]
  cameras:
    - {id: w0, homography: [1, 2, 3, 2, 4, 6, 0, 0, 1]}
YAML
expect_exit 2 "a degenerate homography is refused" -- "$bin/estimator_node" --surface "$work/degenerate.yaml" --no-dds \
  --in-features "$work/sim/w0.jsonl" --out-strokes "$work/x.jsonl"
expect_stderr_contains "degenerate.yaml: surface.cameras[0].homography" "the error names the file and key"
sed 's/origin: \[0.0, 0.0, 0.0\]/origin: [0.0, -3.0, 0.0]/' "$surface" >"$work/behind.yaml"
expect_exit 2 "a plane behind the cameras is refused" -- "$bin/estimator_node" --surface "$work/behind.yaml" \
  --calibration "$cal" --no-dds --in-features "$work/sim/w0.jsonl" --out-strokes "$work/x.jsonl"
expect_stderr_contains "behind.yaml: surface.plane" "the error names the file and key"
expect_stderr_contains "behind" "and says the plane is behind the camera"

# --- offline: the same features, deterministic ----------------------------------------------------
# (the `surface:` section inside the estimator's --config file, beside its other settings)
{ printf 'node: {status_period_s: 1}\n'; cat "$surface"; } >"$work/config.yaml"
expect_exit 0 "offline surface mode (surface: in --config)" -- "$bin/estimator_node" --config "$work/config.yaml" \
  --calibration "$cal" --no-dds --in-features "$work"/sim/w*.jsonl --out-strokes "$work/offline.jsonl"
expect_stderr_matches "surface_off_surface [1-9][0-9]+" "the spot below the wall is counted off the surface"

# --- calibrate surface: homographies from known points (their pixels projected through the
# simulator's calibration), then the offline run on those homographies alone (no --calibration) --
python3 - "$cal" >"$work/points.yaml" <<'PYTHON'
import sys, yaml
cal = yaml.safe_load(open(sys.argv[1]))
print("size: [3.0, 1.0]\ncameras:")
for camera in cal["cameras"]:
    fx, fy, cx, cy = camera["K"]
    (qx, qy, qz, qw), t = camera["T_world_cam"]["q"], camera["T_world_cam"]["t"]
    # R_world_cam from the quaternion; p_cam = R^T (p - t)
    R = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
         [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
         [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    print(f"  - id: {camera['id']}\n    points:")
    for ds, dt in [(-0.5, 0.1), (0.5, 0.1), (0.5, 0.9), (-0.5, 0.9), (0.0, 0.5), (0.3, 0.3)]:
        s, height = t[0] + ds, dt  # the wall point (x = s, y = 0, z = t)
        d = [s - t[0], 0.0 - t[1], height - t[2]]
        x, y, z = (sum(R[r][c] * d[r] for r in range(3)) for c in range(3))
        print(f"      - {{surface: [{s}, {height}], pixel: [{fx * x / z + cx}, {fy * y / z + cy}]}}")
PYTHON
expect_exit 0 "calibrate surface from known points" -- "$bin/estimator_node" calibrate surface --points "$work/points.yaml" \
  --out "$work/wall.yaml"
grep -E "camera w[0-2]: 6 points, residual RMS 0\.00[0-9] mm" "$work/last.err" | wc -l | grep -qx 3 &&
  pass "each camera's homography explains its points (residual < 0.01 mm)" || { fail "residuals"; cat "$work/last.err"; }
expect_exit 0 "offline surface mode on the fitted homographies alone" -- "$bin/estimator_node" --surface "$work/wall.yaml" \
  --no-dds --in-features "$work"/sim/w*.jsonl --out-strokes "$work/homography.jsonl"
printf 'size: [3, 1]\ncameras:\n  - {id: w0, corners: [[0, 0], [1, 1], [2, 2], [3, 4]]}\n' >"$work/collinear.yaml"
expect_exit 2 "three collinear corners are refused" -- "$bin/estimator_node" calibrate surface --points "$work/collinear.yaml" \
  --out "$work/x.yaml"
expect_stderr_contains "collinear.yaml: cameras[0].corners" "the error names the file and key"

# --- live: three camera_nodes -> estimator_node --surface -> lumipoint_board ------------------------
"$bin/lumipoint_board" --out "$work/board.ppm" --events "$work/events.jsonl" --duration 20 --idle-exit 2 \
  >"$work/board.log" 2>&1 &
board=$!
pids+=("$board")
# The Python binding reads the same strokes (docs/clients.md).
python=$(cat "$build_dir/python/INTERPRETER" 2>/dev/null)
if [ -n "$python" ] && [ -f "$build_dir/python/panoptes/__init__.py" ]; then
  PYTHONPATH="$build_dir/python" "$python" - "$work/python.txt" >"$work/python.log" 2>&1 <<'PYTHON' &
import collections, sys, panoptes
phases = collections.Counter()
with panoptes.Client() as client:
    while True:
        stroke = client.wait_for_stroke(2.0 if phases else 20.0)
        if stroke is None:
            break
        phases[stroke.phase] += 1
        assert len(stroke.position) == 2 and stroke.surface_size == (3.0, 1.0), stroke
open(sys.argv[1], "w").write(f"{phases['begin']} {phases['continue']} {phases['end']}\n")
PYTHON
  python_reader=$!
  pids+=("$python_reader")
fi
"$bin/panoptes_track_probe" --status --out "$work/status.jsonl" --duration 14 >"$work/probe.log" 2>&1 &
pids+=("$!")
"$bin/estimator_node" --surface "$live_surface" --calibration "$cal" --duration 12 --status-period 1 \
  --out-strokes "$work/live.jsonl" >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
# The 6 s scene starts 3-4 s from now (a fixed 2 s wait before this until issue 31: the epoch's lead
# alone covers the estimator's start) and ends 2-3 s before the estimator.
epoch=$(( ($(date +%s) + 4) * 1000000000 ))
replay_cameras "$epoch" 11 w0 w1 w2
timeout 20 tail -s 0.05 --pid="$estimator" -f /dev/null
wait "$estimator"
rc=$?
[ "$rc" -eq 0 ] && pass "estimator_node --surface exited cleanly" || { fail "estimator exit $rc"; tail -5 "$work/estimator.log"; }
timeout 20 tail -s 0.05 --pid="$board" -f /dev/null
wait "$board" && pass "lumipoint_board wrote its board" || { fail "lumipoint_board exit $?"; cat "$work/board.log"; }
cat "$work/board.log"
if [ -n "${python_reader:-}" ]; then
  timeout 20 tail -s 0.05 --pid="$python_reader" -f /dev/null
  expected="$(python3 -c "
import collections, json, sys
c = collections.Counter(json.loads(l)['phase'] for l in open('$work/live.jsonl'))
print(c['begin'], c['continue'], c['end'])")"
  [ "$(cat "$work/python.txt" 2>/dev/null)" = "$expected" ] && pass "the Python binding received every stroke event ($expected)" ||
    { fail "Python reader: '$(cat "$work/python.txt" 2>/dev/null)', expected '$expected'"; cat "$work/python.log"; }
fi
grep "surface mode:" "$work/estimator.log"
python3 - "$work/status.jsonl" <<'PYTHON' || failures=$((failures + 1))
import json, sys
status = [json.loads(l) for l in open(sys.argv[1]) if '"status"' in l]
last = status[-1]["counters"] if status else {}
ok = last.get("surface_strokes_begun") == 10 and last.get("surface_off_surface", 0) > 100 and last.get("surface_frames", 0) >= 1700
print(("PASS: " if ok else "FAIL: ") + "estimator_status counts the strokes and the spots off the surface: " +
      ", ".join(f"{k} {v}" for k, v in sorted(last.items()) if k.startswith("surface_")))
sys.exit(0 if ok else 1)
PYTHON

python3 "$source_dir/tests/integration/surface_check.py" "$work" "$scene" "$epoch"
[ $? -eq 0 ] || failures=$((failures + 1))
finish
