#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `estimator_node calibrate`: chessboard intrinsics against OpenCV's own figures, wand solve on
# simulated features (report files, accuracy against the truth), world frame from an L-frame, a
# 2-marker bar, a single LED scaled by the L-frame, the world frame (and scale) from the wand laid on
# the floor, and the errors a user gets for bad input. No DDS.
source "$(dirname "$0")/lib.sh"
en="$bin/estimator_node"

# --- help and bad arguments ---------------------------------------------------------------------
expect_exit 0 "calibrate --help" -- "$en" calibrate --help
for sub in intrinsics solve world capture import-points; do
  expect_exit 0 "calibrate $sub --help" -- "$en" calibrate "$sub" --help
done
expect_exit 2 "unknown subcommand" -- "$en" calibrate bogus
expect_stderr_contains "unknown subcommand 'bogus'" "the error names the subcommand"

# --- intrinsics on Debian's opencv-doc stereo images -------------------------------------------
data=/usr/share/doc/opencv-doc/examples/data
if ls "$data"/left0*.jpg >/dev/null 2>&1; then
  for side in left right; do
    expect_exit 0 "intrinsics of the $side images" -- "$en" calibrate intrinsics --images "$data/${side}*.jpg" \
      --board 9x6 --square 0.025 --out "$work/intrinsics.yaml" --id "$side"
    rms=$(sed -n 's/.*RMS reprojection error \([0-9.]*\) px.*/\1/p' "$work/last.out")
    # OpenCV's calibrateCamera on these images: 0.41 px (left), 0.46 px (right).
    expected=$([ "$side" = left ] && echo 0.41 || echo 0.46)
    if awk -v a="$rms" -v b="$expected" 'BEGIN { exit !(a > b - 0.01 && a < b + 0.01) }'; then
      pass "$side RMS $rms px matches OpenCV's $expected px"
    else
      fail "$side RMS '$rms' px, OpenCV gives $expected px"
    fi
  done
  # A glob(3) bracket expression (cv::glob, used before, did not understand it): the 13 numbered
  # images, without left.jpg.
  expect_exit 0 "intrinsics of 'left[0-9]*.jpg'" -- "$en" calibrate intrinsics --images "$data/left[0-9]*.jpg" \
    --board 9x6 --square 0.025 --out "$work/intrinsics.yaml" --id left
  grep -q "board found in 13 of 13 images" "$work/last.out" "$work/last.err" &&
    pass "the bracket pattern selects the 13 numbered images" || fail "the bracket pattern: $(cat "$work/last.out")"
else
  echo "SKIP: opencv-doc is not installed (deploy/install-deps.sh installs it)"
fi
expect_exit 2 "intrinsics: no image matches" -- "$en" calibrate intrinsics --images "$work/none*.png" --board 9x6 \
  --square 0.02 --out "$work/x.yaml"
expect_stderr_contains "no file matches" "the error names the glob"

# --- wand solve on a simulated room ------------------------------------------------------------
cp "$source_dir/deploy/scenes/wand_room.yaml" "$work/room.yaml"
expect_exit 0 "simulate wand features" -- "$bin/panoptes_sim" features --scene "$work/room.yaml" --out-dir "$work/wand"
expect_exit 0 "calibrate solve" -- "$en" calibrate solve --cameras "$work/wand/calibration.yaml" \
  --in-features "$work"/wand/cam*.jsonl --wand 0,0.18,0.5 --out "$work/cal.yaml"
cat "$work/last.out"
for f in cal.yaml cal.report.txt cal.report.json cal.residuals.png cal.layout.png cal.coverage_cam0.png cal.coverage_cam5.png; do
  [ -s "$work/$f" ] && pass "wrote $f" || fail "missing $f"
done
grep -q "T_world_cam" "$work/cal.yaml" && pass "cal.yaml has camera poses" || fail "cal.yaml lacks T_world_cam"
expect_exit 0 "the estimator accepts the solved calibration" -- "$en" --calibration "$work/cal.yaml" \
  --in-features "$work"/wand/cam*.jsonl --no-dds --out-tracks "$work/tracks.jsonl" --quiet

# --- world frame from an L-frame on the floor: the result must land on the true poses -------------
sed -e 's/^bodies:$/markers:/' -e '/name: wand/,$d' "$work/room.yaml" >"$work/lframe.yaml"
cat >>"$work/lframe.yaml" <<'YAML'
  - {name: corner, path: {type: static, position: [0, 0, 0.0]}}
  - {name: xarm, path: {type: static, position: [0.5, 0, 0.0]}}
  - {name: yarm, path: {type: static, position: [0, 0.3, 0.0]}}
YAML
expect_exit 0 "simulate the L-frame" -- "$bin/panoptes_sim" features --scene "$work/lframe.yaml" --out-dir "$work/lf" --duration 0.5
expect_exit 0 "calibrate world --lframe" -- "$en" calibrate world --calibration "$work/cal.yaml" \
  --in-features "$work"/lf/cam*.jsonl --lframe 0.5,0.3 --out "$work/cal_world.yaml"

cat "$work/last.out"
# largest_position_error CALIBRATION TRUTH LIMIT_M: prints the largest camera-centre distance and
# succeeds if it is below LIMIT_M.
largest_position_error() {
  python3 - "$1" "$2" "$3" <<'PY'
import sys, re, math
def centres(path):
    text = open(path).read()
    out = {}
    for block in text.split("- id:")[1:]:
        name = block.split("\n")[0].strip().strip('"')
        m = re.search(r"t: \[([^\]]*)\]", block)
        if m: out[name] = [float(v) for v in m.group(1).split(",")]
    return out
est, true = centres(sys.argv[1]), centres(sys.argv[2])
worst = max(math.dist(est[k], true[k]) for k in true)
print(f"largest camera position error after calibrate world: {worst * 1000:.2f} mm")
sys.exit(0 if worst < float(sys.argv[3]) else 1)
PY
}
# expect_cameras_within CALIBRATION LIMIT_M DESCRIPTION: every camera centre within LIMIT_M of the
# simulated truth.
expect_cameras_within() {
  if largest_position_error "$1" "$work/wand/calibration.yaml" "$2"; then pass "$3"; else fail "$3"; fi
}
# expect_contains PATTERN FILE DESCRIPTION (grep -q)
expect_contains() {
  if grep -q -- "$1" "$2"; then pass "$3"; else fail "$3: $2 lacks '$1'"; fi
}
expect_cameras_within "$work/cal_world.yaml" 0.005 "world frame from the L-frame matches the true frame within 5 mm"
expect_contains "scale check (the L-frame's arms against --lframe): the calibration's scale is" "$work/last.out" \
  "calibrate world --lframe checks the calibration's scale against the arms"
if grep -q "WARNING: scale check" "$work/last.out"; then fail "the right scale warned"; else pass "the right scale does not warn"; fi
# The same calibration scaled by 0.3% about the origin (every camera centre): the arms measure 3000 ppm long.
python3 - "$work/cal.yaml" "$work/cal_scaled.yaml" <<'PY'
import re, sys
scale = lambda m: "t: [" + ", ".join(repr(float(v) * 1.003) for v in m.group(1).split(",")) + "]"
open(sys.argv[2], "w").write(re.sub(r"t: \[([^\]]*)\]", scale, open(sys.argv[1]).read()))
PY
expect_exit 0 "calibrate world --lframe on a calibration 0.3% too large" -- "$en" calibrate world \
  --calibration "$work/cal_scaled.yaml" --in-features "$work"/lf/cam*.jsonl --lframe 0.5,0.3 --out "$work/cal_scaled_world.yaml"
expect_contains "WARNING: scale check" "$work/last.out" "a calibration 0.3% too large warns"
expect_exit 0 "--scale-tolerance 0.005 accepts it" -- "$en" calibrate world --calibration "$work/cal_scaled.yaml" \
  --in-features "$work"/lf/cam*.jsonl --lframe 0.5,0.3 --out "$work/cal_scaled_world.yaml" --scale-tolerance 0.005
if grep -q "WARNING: scale check" "$work/last.out"; then fail "--scale-tolerance 0.005 still warned"; else pass "--scale-tolerance 0.005 does not warn"; fi
expect_contains "focal length and depth" "$work/cal.report.txt" "the solve report has the focal length and depth table"
expect_contains '"focal_depth"' "$work/cal.report.json" "report.json has focal_depth per camera"
expect_contains '"predicted_rms_error_mm"' "$work/cal.report.json" "report.json has the predicted wand-length RMS"

# --- a 2-marker bar: its ends look alike; the cameras' label runs are reconciled ----------------
sed 's/markers: \[\[-0.25, 0, 0\], \[-0.07, 0, 0\], \[0.25, 0, 0\]\]/markers: [[-0.25, 0, 0], [0.25, 0, 0]]/' \
  "$work/room.yaml" >"$work/bar.yaml"
grep -q "markers: \[\[-0.25, 0, 0\], \[0.25, 0, 0\]\]" "$work/bar.yaml" || fail "bar.yaml: the wand was not replaced"
expect_exit 0 "simulate a 2-marker bar" -- "$bin/panoptes_sim" features --scene "$work/bar.yaml" --out-dir "$work/bar"
expect_exit 0 "calibrate solve --wand 0,0.5" -- "$en" calibrate solve --cameras "$work/bar/calibration.yaml" \
  --in-features "$work"/bar/cam*.jsonl --wand 0,0.5 --out "$work/bar_cal.yaml"
grep "bar ends\|wand length" "$work/last.out"
grep -q "bar ends (they look alike)" "$work/last.out" && pass "the report tells how the bar's ends were labelled" ||
  fail "no bar-ends line in the report"
expect_exit 0 "calibrate world on the bar calibration" -- "$en" calibrate world --calibration "$work/bar_cal.yaml" \
  --in-features "$work"/lf/cam*.jsonl --lframe 0.5,0.3 --out "$work/bar_world.yaml"
expect_cameras_within "$work/bar_world.yaml" 0.005 "2-marker bar: cameras within 5 mm of the truth in the L-frame's world"

# --- a single LED (seed 003): no scale until the L-frame's arms give it ------------------------
sed 's/markers: \[\[-0.25, 0, 0\], \[-0.07, 0, 0\], \[0.25, 0, 0\]\]/markers: [[0, 0, 0]]/' \
  "$work/room.yaml" >"$work/led.yaml"
expect_exit 0 "simulate a single LED" -- "$bin/panoptes_sim" features --scene "$work/led.yaml" --out-dir "$work/led"
expect_exit 0 "calibrate solve --wand 0" -- "$en" calibrate solve --cameras "$work/led/calibration.yaml" \
  --in-features "$work"/led/cam*.jsonl --wand 0 --out "$work/led_cal.yaml"
grep -q "^# UNSCALED" "$work/led_cal.yaml" && pass "the single-LED calibration is marked UNSCALED" ||
  fail "led_cal.yaml is not marked UNSCALED"
grep -q "UNSCALED" "$work/last.out" && pass "the summary says it is unscaled" || fail "the summary does not say UNSCALED"
expect_exit 2 "calibrate world --floor on an unscaled calibration" -- "$en" calibrate world \
  --calibration "$work/led_cal.yaml" --in-features "$work"/lf/cam*.jsonl --floor --out "$work/led_world.yaml"
expect_stderr_contains "is unscaled" "the error says the calibration is unscaled and what to give"
expect_exit 0 "calibrate world --lframe sets the scale" -- "$en" calibrate world --calibration "$work/led_cal.yaml" \
  --in-features "$work"/lf/cam*.jsonl --lframe 0.5,0.3 --out "$work/led_world.yaml"
cat "$work/last.out"
expect_contains "metric scale set from the L-frame" "$work/last.out" "calibrate world reports the scale"
grep -q "UNSCALED" "$work/led_world.yaml" && fail "led_world.yaml is still marked UNSCALED" ||
  pass "the scaled calibration is no longer marked UNSCALED"
expect_cameras_within "$work/led_world.yaml" 0.005 "single LED + L-frame: cameras within 5 mm of the truth"

# --- world frame from the wand laid on the floor (--wand-floor) ----------------------------------
# The first rest puts the wand's first marker on the true origin, along +x: the frames must agree.
floor_recording floor \
  "[0.25, 0, 0.007], [0.25, 0, 0.007], [-0.8, 0.5, 0.007], [-0.8, 0.5, 0.007], [0.9, 0.8, 0.007], [0.9, 0.8, 0.007], [-0.5, -0.9, 0.007], [-0.5, -0.9, 0.007]" \
  "[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0.564642, 0.825336], [0, 0, 0.564642, 0.825336], [0, 0, -0.29552, 0.955336], [0, 0, -0.29552, 0.955336], [0, 0, 0.841471, 0.540302], [0, 0, 0.841471, 0.540302]"
expect_exit 0 "calibrate world --wand-floor" -- "$en" calibrate world --calibration "$work/cal.yaml" \
  --in-features "$work"/floor/cam*.jsonl --wand 0,0.18,0.5 --wand-floor --floor-offset 0.007 \
  --out "$work/floor_world.yaml"
cat "$work/last.out"
expect_contains "4 placements" "$work/last.out" "the four placements were found"
expect_contains "plane RMS" "$work/floor_world.world.txt" "wrote floor_world.world.txt with the plane RMS"
expect_cameras_within "$work/floor_world.yaml" 0.001 "world frame from the wand on the floor matches the true frame within 1 mm"
expect_contains "scale check (the wand's median length on the floor against --wand): the calibration's scale is" \
  "$work/floor_world.world.txt" "--wand-floor checks the scale against the wand's length, in the report"
if grep -q "WARNING: scale check" "$work/last.out"; then fail "--wand-floor: the right scale warned"; else pass "--wand-floor: the right scale does not warn"; fi
expect_exit 0 "--wand-floor on a calibration 0.3% too large" -- "$en" calibrate world --calibration "$work/cal_scaled.yaml" \
  --in-features "$work"/floor/cam*.jsonl --wand 0,0.18,0.5 --wand-floor --floor-offset 0.007 --out "$work/floor_scaled.yaml"
expect_contains "WARNING: scale check (the wand's median length" "$work/last.out" "--wand-floor: a calibration 0.3% too large warns"
expect_exit 0 "--wand-floor scales an unscaled (single-LED) calibration" -- "$en" calibrate world \
  --calibration "$work/led_cal.yaml" --in-features "$work"/floor/cam*.jsonl --wand 0,0.18,0.5 --wand-floor \
  --floor-offset 0.007 --out "$work/led_floor.yaml"
expect_contains "metric scale set from the wand's length" "$work/last.out" "the wand's length set the scale"
expect_cameras_within "$work/led_floor.yaml" 0.001 "single LED + wand on the floor: cameras within 1 mm of the truth"
expect_exit 2 "--wand-floor excludes --floor" -- "$en" calibrate world --calibration "$work/cal.yaml" \
  --in-features "$work"/floor/cam*.jsonl --wand 0,0.18,0.5 --wand-floor --floor --out "$work/bad.yaml"
expect_exit 2 "--wand-floor needs --wand" -- "$en" calibrate world --calibration "$work/cal.yaml" \
  --in-features "$work"/floor/cam*.jsonl --wand-floor --out "$work/bad.yaml"
expect_stderr_contains "--wand" "the error names --wand"
expect_exit 2 "--wand-floor with a single light" -- "$en" calibrate world --calibration "$work/cal.yaml" \
  --in-features "$work"/floor/cam*.jsonl --wand 0 --wand-floor --out "$work/bad.yaml"
expect_stderr_contains "two or more markers" "the error says the wand needs two markers"
# Laid end to end along one line: the floor's roll is unknown.
floor_recording line \
  "[-1, 0.1, 0.007], [-1, 0.1, 0.007], [-0.3, 0.1, 0.007], [-0.3, 0.1, 0.007], [0.4, 0.1, 0.007], [0.4, 0.1, 0.007], [1, 0.1, 0.007], [1, 0.1, 0.007]" \
  "[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1]"
expect_exit 1 "collinear placements are refused" -- "$en" calibrate world --calibration "$work/cal.yaml" \
  --in-features "$work"/line/cam*.jsonl --wand 0,0.18,0.5 --wand-floor --out "$work/bad.yaml"
expect_stderr_contains "on one line" "the error says the positions are on one line"
expect_stderr_contains "line/cam0.jsonl" "the error names the recording"

# --- bad input ----------------------------------------------------------------------------------
expect_exit 2 "malformed --wand" -- "$en" calibrate solve --cameras "$work/wand/calibration.yaml" \
  --in-features "$work/wand/cam0.jsonl" --wand 0,x,0.5 --out "$work/bad.yaml"
expect_stderr_contains "'x' is not a number" "the error names the bad wand value"
expect_exit 2 "missing intrinsics file" -- "$en" calibrate solve --cameras "$work/none.yaml" \
  --in-features "$work/wand/cam0.jsonl" --wand 0,0.18,0.5 --out "$work/bad.yaml"
expect_stderr_contains "none.yaml" "the error names the file"
# cam3's features left out: the others are calibrated, cam3 is named, partial results written.
expect_exit 1 "a camera without features" -- "$en" calibrate solve --cameras "$work/wand/calibration.yaml" \
  --in-features "$work"/wand/cam[0-2].jsonl "$work"/wand/cam[4-5].jsonl --wand 0,0.18,0.5 --out "$work/partial.yaml"
expect_stderr_contains "cam3: no features" "the error names cam3 and the reason"
grep -q "NOT CALIBRATED (no T_world_cam): cam3" "$work/partial.yaml" && pass "partial.yaml marks cam3" || fail "partial.yaml does not mark cam3"
expect_exit 1 "wrong wand spacing" -- "$en" calibrate solve --cameras "$work/wand/calibration.yaml" \
  --in-features "$work"/wand/cam*.jsonl --wand 0,0.3,0.5 --out "$work/wrong.yaml"
expect_stderr_contains "lengths never match" "the error says the lengths never match"

# --- real single-point data (issue 16): no flags from a focal length 30% off; x3 is refused ----------
selfcal="$source_dir/../shared/data/selfcal_4cam"
require_shared_data "$selfcal/points.dat"
expect_exit 0 "calibrate import-points" -- "$en" calibrate import-points --points "$selfcal/points.dat" \
  --resolutions "$selfcal/Res.dat" --focal 1300 --out-features "$work/points.jsonl" --out-cameras "$work/points_cameras.yaml"
grep -q "nominal: true" "$work/points_cameras.yaml" && pass "the imported cameras are marked nominal" ||
  fail "points_cameras.yaml lacks nominal: true"
expect_exit 0 "calibrate solve on the real set without flags" -- "$en" calibrate solve \
  --cameras "$work/points_cameras.yaml" --in-features "$work/points.jsonl" --wand 0 --out "$work/real.yaml"
expect_contains "intrinsics refined automatically" "$work/last.out" "the summary says the intrinsics were refined"
expect_contains "converged in every pass" "$work/last.out" "the summary says the adjustment converged"
expect_contains "raw-frame reprojection error, 2D, px" "$work/last.out" "the headline is the raw-frame 2D error"
expect_exit 0 "import-points with focal x3" -- "$en" calibrate import-points --points "$selfcal/points.dat" \
  --resolutions "$selfcal/Res.dat" --focal 3000 --out-features "$work/points3.jsonl" --out-cameras "$work/points_x3.yaml"
expect_exit 1 "calibrate solve refuses a focal length 3x wrong" -- "$en" calibrate solve \
  --cameras "$work/points_x3.yaml" --in-features "$work/points3.jsonl" --wand 0 --out "$work/x3.yaml"
expect_stderr_contains "cam2: focal length" "the error names the camera"
expect_stderr_contains "check K" "the error says what to check"

# --- versions (issue 36 item 5, docs/calibration.md "Versions") ----------------------------------
cp "$work/cal.yaml" "$work/versioned.yaml"
cp "$work/cal.yaml" "$work/before.yaml"
expect_exit 0 "calibrate history --start" -- "$en" calibrate history --calibration "$work/versioned.yaml" --start
expect_exit 0 "calibrate world onto a file with a history" -- "$en" calibrate world --calibration "$work/versioned.yaml" \
  --in-features "$work"/lf/cam*.jsonl --lframe 0.5,0.3 --out "$work/versioned.yaml"
expect_exit 0 "calibrate history --json" -- "$en" calibrate history --calibration "$work/versioned.yaml" --json
python3 - "$work/last.out" <<'PY' && pass "two versions: initial, then calibrate world touching every camera" || fail "history: $(cat "$work/last.out")"
import json, sys
v = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
sys.exit(0 if [x["reason"] for x in v] == ["initial", "calibrate world"] and len(v[1]["cameras"]) >= 4 else 1)
PY
cmp -s "$work/versioned.yaml" "$work/cal_world.yaml" && pass "the versioned file equals the plain calibrate world output" ||
  fail "versioned calibrate world differs from the plain one"
expect_exit 0 "calibrate revert --version 1" -- "$en" calibrate revert --calibration "$work/versioned.yaml" --version 1
cmp -s "$work/versioned.yaml" "$work/before.yaml" && pass "revert restores the exact earlier file" || fail "revert: bytes differ"
grep -Eq "^v2 .* reverted +calibrate world" "$work/last.out" && pass "the reverted version is marked" || fail "no reverted v2: $(cat "$work/last.out")"
expect_exit 2 "a version that does not exist" -- "$en" calibrate revert --calibration "$work/versioned.yaml" --version 9
expect_stderr_contains "history.jsonl: version: no version 9 (3 stored)" "the error names the history and the version"

finish
