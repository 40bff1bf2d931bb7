#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# camera_node and bad input: a missing device or file and a bad configuration stop it at start-up
# with one line naming what is wrong (exit 2); corrupt, truncated and empty image files in
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
