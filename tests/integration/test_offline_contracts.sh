#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The offline contracts (architecture.md): images -> features JSONL, features JSONL -> tracks JSONL,
# and the errors a user gets for bad input.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/demo.yaml"

# --- images -> features -------------------------------------------------------------------------
expect_exit 0 "render 20 frames of cam0" -- "$bin/panoptes_sim" render --scene "$scene" --camera cam0 --frames 20 --out-dir "$work/images"
expect_exit 0 "camera_node detects blobs in image files" -- \
  "$bin/camera_node" --source "images:$work/images" --no-dds --out-features "$work/images.jsonl" --quiet
lines=$(wc -l <"$work/images.jsonl")
[ "$lines" -eq 20 ] && pass "one FeatureFrame per image ($lines)" || fail "expected 20 FeatureFrames, got $lines"
if grep -q '"camera_id"' "$work/images.jsonl" && grep -q '"stamp_ns"' "$work/images.jsonl" && grep -q '"x"' "$work/images.jsonl"; then
  pass "FeatureFrame lines carry camera_id, stamp_ns and blobs"
else
  fail "FeatureFrame lines lack contract keys"; head -2 "$work/images.jsonl"
fi
expect_exit 0 "camera_node accepts a glob" -- \
  "$bin/camera_node" --source "images:$work/images/frame_00000*.pgm" --no-dds --out-features "$work/glob.jsonl" --quiet
[ "$(wc -l <"$work/glob.jsonl")" -eq 10 ] && pass "glob selects 10 images" || fail "glob selected $(wc -l <"$work/glob.jsonl") images"

# --- features -> tracks -------------------------------------------------------------------------
expect_exit 0 "simulate 6 s of features" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 6
expect_exit 0 "offline estimator" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --in-features "$work"/sim/cam*.jsonl --no-dds --out-tracks "$work/tracks.jsonl" --quiet
expect_exit 0 "offline tracks meet the demo targets" -- "$bin/panoptes_eval" --scene "$scene" --tracks "$work/tracks.jsonl" \
  --require-rmse-mm 2 --require-tracked 0.95 --require-no-id-switches --summary-json "$work/eval.json"
cat "$work/last.out"
# Deterministic: a second run writes the same bytes.
"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --in-features "$work"/sim/cam*.jsonl --no-dds \
  --out-tracks "$work/tracks2.jsonl" --quiet 2>/dev/null
cmp -s "$work/tracks.jsonl" "$work/tracks2.jsonl" && pass "offline estimator is deterministic" || fail "two offline runs differ"

# --- bad input ----------------------------------------------------------------------------------
expect_exit 0 "camera_node --help" -- "$bin/camera_node" --help
expect_exit 0 "estimator_node --help" -- "$bin/estimator_node" --help
expect_exit 2 "camera_node rejects an unknown flag" -- "$bin/camera_node" --source images:/tmp --frobnicate
[ "$(wc -l <"$work/last.err")" -eq 1 ] && pass "one-line reason for a bad flag" || fail "bad flag gave $(wc -l <"$work/last.err") lines"
expect_exit 2 "estimator_node without --calibration offline" -- "$bin/estimator_node" --no-dds --in-features "$work/sim/cam0.jsonl"
expect_exit 2 "missing calibration file" -- "$bin/estimator_node" --calibration "$work/nope.yaml" --no-dds \
  --in-features "$work/sim/cam0.jsonl" --out-tracks "$work/x.jsonl"
expect_stderr_contains "nope.yaml" "the missing calibration file is named"
sed 's/^\(\s*\)K:/\1Kx:/' "$work/sim/calibration.yaml" >"$work/bad_cal.yaml"
expect_exit 2 "calibration without K" -- "$bin/estimator_node" --calibration "$work/bad_cal.yaml" --no-dds \
  --in-features "$work/sim/cam0.jsonl" --out-tracks "$work/x.jsonl"
expect_stderr_contains "bad_cal.yaml" "the bad calibration file is named"
expect_stderr_contains "K" "the missing key is named"
expect_exit 2 "missing image directory" -- "$bin/camera_node" --source "images:$work/no-such-dir" --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "no-such-dir" "the missing image directory is named"
expect_exit 2 "missing features file" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --no-dds \
  --in-features "$work/none.jsonl" --out-tracks "$work/x.jsonl"
expect_stderr_contains "none.jsonl" "the missing features file is named"
# Malformed lines are counted and skipped, never a crash.
{ head -50 "$work/sim/cam0.jsonl"; echo 'not json'; echo '{"camera_id": "cam0"}'; echo '{"camera_id":"cam0","frame":1,"stamp_ns":"x","blobs":[]}'; } >"$work/mangled.jsonl"
expect_exit 0 "malformed feature lines are skipped" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --no-dds --in-features "$work/mangled.jsonl" --out-tracks "$work/x.jsonl"
expect_stderr_contains "mangled.jsonl:51" "the first malformed line is reported with file and line"
# Frames from a camera with no calibration are counted and warned about once.
sed 's/"cam0"/"cam9"/' "$work/sim/cam0.jsonl" >"$work/cam9.jsonl"
expect_exit 0 "features from an uncalibrated camera" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --no-dds --in-features "$work/cam9.jsonl" --out-tracks "$work/x.jsonl"
warnings=$(grep -c "camera 'cam9' has no calibration" "$work/last.err")
[ "$warnings" -eq 1 ] && pass "uncalibrated camera warned about once" || fail "warnings: $warnings"
grep -q "camera cam9: frames [0-9]* used 0 .*utilisation 0.0000" "$work/last.err" &&
  grep -q "uncalibrated_camera=" "$work/last.err" && pass "its frames are counted as unused, by reason" ||
  fail "no usage line for cam9"
expect_stderr_contains "from uncalibrated cameras" "uncalibrated frames are counted"
finish
