#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# camera_node and bad input: a missing device or file, a bad configuration and GenICam timing
# features the camera lacks stop it at start-up with one line naming what is wrong (exit 2); corrupt, truncated and empty image files in
# a stream are counted and skipped while the node carries on.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/demo.yaml"

expect_exit 2 "a missing V4L2 device is a start-up error" -- \
  "$bin/camera_node" --source v4l2:/dev/video9 --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "v4l2:/dev/video9: cannot open" "the error names the device"
[ "$(wc -l <"$work/last.err")" -eq 1 ] && pass "the error is one line" || fail "error is $(wc -l <"$work/last.err") lines"

expect_exit 2 "a missing feature file is a start-up error" -- \
  "$bin/camera_node" --source features:"$work/none.jsonl" --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "none.jsonl" "the error names the file"

printf 'detector:\n  treshold: 40\n' >"$work/typo.yaml"
expect_exit 2 "an unknown configuration key is rejected" -- \
  "$bin/camera_node" --source "sim:$scene#cam0" --config "$work/typo.yaml" --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "typo.yaml: detector.treshold: unknown key" "the error names file and key"
printf 'source:\n  buffers: 1\n' >"$work/range.yaml"
expect_exit 2 "an out-of-range value is rejected" -- \
  "$bin/camera_node" --source "sim:$scene#cam0" --config "$work/range.yaml" --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "range.yaml: source.buffers: must be between 2 and 256" "the error names file, key and range"
printf 'camera: {}\n' >"$work/section.yaml"
expect_exit 2 "an unknown section is rejected" -- \
  "$bin/camera_node" --source "sim:$scene#cam0" --config "$work/section.yaml" --no-dds --out-features "$work/x.jsonl"

# GenICam timing features the camera lacks (Aravis's in-process fake camera, "Fake_1": only the
# Fake interface is enabled for it, so nothing touches the network): exit 2 naming the feature
# and the camera.
expect_exit 2 "PTP on a camera without it is a start-up error" -- \
  "$bin/camera_node" --source aravis:Fake_1 --ptp on --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:Fake_1: ptp: the camera has neither PtpEnable nor GevIEEE1588" "the error names camera and features"
expect_exit 2 "a strobe on a camera without output lines is a start-up error" -- \
  "$bin/camera_node" --source aravis:Fake_1 --strobe Line1 --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:Fake_1: strobe Line1: the camera has no LineSelector feature" "the error names camera and feature"
expect_exit 2 "a trigger edge the camera lacks is a start-up error" -- \
  "$bin/camera_node" --source aravis:Fake_1 --trigger Line0 --trigger-activation FallingEdge --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "TriggerActivation has no entry FallingEdge (the camera offers RisingEdge)" "the error names the feature and what it offers"
expect_exit 2 "a trigger source the camera lacks is a start-up error" -- \
  "$bin/camera_node" --source aravis:Fake_1 --trigger Line9 --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "aravis:Fake_1: trigger Line9: TriggerSource has no entry Line9" "the error names camera and feature"
printf 'source:\n  ptp: on\n' >"$work/ptp.yaml"
expect_exit 2 "PTP on a source that is no GenICam camera is refused" -- \
  "$bin/camera_node" --source "sim:$scene#cam0" --config "$work/ptp.yaml" --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "only aravis: sources have them" "the error says which sources have the features"
printf 'source:\n  trigger: Line0\n  frame_rate_hz: 30\n' >"$work/trigger_rate.yaml"
expect_exit 2 "a trigger with a frame rate is refused" -- \
  "$bin/camera_node" --source aravis:Fake_1 --config "$work/trigger_rate.yaml" --no-dds --out-features "$work/x.jsonl"
expect_stderr_contains "trigger_rate.yaml: source.frame_rate_hz: a triggered camera runs at its trigger's rate" "the error names file and key"
expect_exit 0 "a trigger the camera has is configured and frames come" -- \
  "$bin/camera_node" --source aravis:Fake_1 --trigger Line0 --max-frames 2 --no-dds --out-features "$work/triggered.jsonl"
expect_stderr_contains "TriggerSelector=FrameStart TriggerMode=On TriggerSource=Line0 TriggerActivation=RisingEdge" "the features read back are logged"

# A stream with broken files among good ones.
expect_exit 0 "render 6 frames" -- "$bin/panoptes_sim" render --scene "$scene" --camera cam0 --frames 6 --out-dir "$work/images"
first=$(ls "$work"/images/*.pgm | head -1)
head -c 1000 "$first" >"$work/images/frame_000002a.pgm"        # truncated
head -c 5000 /dev/urandom >"$work/images/frame_000003a.pgm"    # garbage
: >"$work/images/frame_000004a.pgm"                            # empty
printf 'P6\n4 4\n255\n%048d' 0 >"$work/images/frame_000005a.pgm"  # colour: converted to grey, not an error
expect_exit 0 "broken files do not stop the node" -- \
  "$bin/camera_node" --source "images:$work/images" --no-dds --out-features "$work/images.jsonl"
[ "$(wc -l <"$work/images.jsonl")" -eq 7 ] && pass "the 6 good frames and the grey-converted colour one are written" || fail "$(wc -l <"$work/images.jsonl") frames written"
expect_stderr_contains "unreadable=3" "the 3 broken files are counted"
expect_stderr_contains "source's last error:" "the last error is reported"
finish
