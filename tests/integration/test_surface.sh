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
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-0}"
for tool in lumipoint_board estimator_node camera_node panoptes_sim; do
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
expect_exit 0 "offline surface mode" -- "$bin/estimator_node" --surface "$surface" --calibration "$cal" --no-dds \
  --in-features "$work"/sim/w*.jsonl --out-strokes "$work/offline.jsonl"

# --- live: three camera_nodes -> estimator_node --surface -> lumipoint_board ------------------------
"$bin/lumipoint_board" --out "$work/board.ppm" --events "$work/events.jsonl" --duration 20 --idle-exit 2 \
  >"$work/board.log" 2>&1 &
board=$!
pids+=("$board")
"$bin/estimator_node" --surface "$surface" --calibration "$cal" --duration 14 --status-period 1 \
  --out-strokes "$work/live.jsonl" >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
sleep 2
epoch=$(( ($(date +%s) + 4) * 1000000000 ))
for camera in w0 w1 w2; do
  "$bin/camera_node" --source "features:$work/sim/$camera.jsonl" --sim-epoch-ns "$epoch" --duration 11 --quiet \
    >"$work/$camera.log" 2>&1 &
  pids+=("$!")
done
timeout 20 tail --pid="$estimator" -f /dev/null
wait "$estimator"
rc=$?
[ "$rc" -eq 0 ] && pass "estimator_node --surface exited cleanly" || { fail "estimator exit $rc"; tail -5 "$work/estimator.log"; }
timeout 20 tail --pid="$board" -f /dev/null
wait "$board" && pass "lumipoint_board wrote its board" || { fail "lumipoint_board exit $?"; cat "$work/board.log"; }
cat "$work/board.log"
grep "surface mode:" "$work/estimator.log"

python3 "$source_dir/tests/integration/surface_check.py" "$work" "$scene" "$epoch"
[ $? -eq 0 ] || failures=$((failures + 1))
finish
