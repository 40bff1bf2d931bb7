#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `estimator_node calibrate`: chessboard intrinsics against OpenCV's own figures, wand solve on
# simulated features (report files, accuracy against the truth), world frame from an L-frame, and
# the errors a user gets for bad input. No DDS.
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
if python3 - "$work/cal_world.yaml" "$work/wand/calibration.yaml" <<'PY'
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
sys.exit(0 if worst < 0.005 else 1)
PY
then pass "world frame from the L-frame matches the true frame within 5 mm"; else fail "world frame off"; fi

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
