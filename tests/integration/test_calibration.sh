#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `estimator_node calibrate`: chessboard intrinsics against OpenCV's own figures, wand solve on
# simulated features (report files, accuracy against the truth), world frame from an L-frame, a
# 2-marker bar, a single LED scaled by the L-frame, and the errors a user gets for bad input. No DDS.
source "$(dirname "$0")/lib.sh"
en="$bin/estimator_node"

# --- help and bad arguments ---------------------------------------------------------------------
expect_exit 0 "calibrate --help" -- "$en" calibrate --help
for sub in intrinsics solve world capture; do
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
if largest_position_error "$work/cal_world.yaml" "$work/wand/calibration.yaml" 0.005; then
  pass "world frame from the L-frame matches the true frame within 5 mm"
else
  fail "world frame off"
fi

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
if largest_position_error "$work/bar_world.yaml" "$work/wand/calibration.yaml" 0.005; then
  pass "2-marker bar: cameras within 5 mm of the truth in the L-frame's world"
else
  fail "2-marker bar calibration off"
fi

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
grep -q "metric scale set from the L-frame" "$work/last.out" && pass "calibrate world reports the scale" ||
  fail "calibrate world did not set the scale"
grep -q "UNSCALED" "$work/led_world.yaml" && fail "led_world.yaml is still marked UNSCALED" ||
  pass "the scaled calibration is no longer marked UNSCALED"
if largest_position_error "$work/led_world.yaml" "$work/wand/calibration.yaml" 0.005; then
  pass "single LED + L-frame: cameras within 5 mm of the truth"
else
  fail "single LED + L-frame calibration off"
fi

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

finish
