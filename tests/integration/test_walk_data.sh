#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Real human motion: the 41-marker walk (tests/data/walk_41markers_100hz.trc) projected into 6
# simulated cameras, tracked by the offline estimator. One pass of the recording (2.37 s); the
# looped scene reverses the recording instantly at each end, which no body can do.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/walk.yaml"
expect_exit 0 "simulate one pass of the walk" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/walk" --duration 2.37
expect_exit 0 "offline estimator on the walk" -- "$bin/estimator_node" --calibration "$work/walk/calibration.yaml" \
  --in-features "$work"/walk/cam*.jsonl --no-dds --out-tracks "$work/tracks.jsonl" --quiet
expect_exit 0 "all 41 markers tracked >= 99%, RMSE < 1.5 mm, no ID switch" -- "$bin/panoptes_eval" --scene "$scene" \
  --tracks "$work/tracks.jsonl" --warmup 0.3 --require-rmse-mm 1.5 --require-tracked 0.99 --require-no-id-switches
tail -1 "$work/last.out"
markers=$(grep -c '^trc/' "$work/last.out")
[ "$markers" -eq 41 ] && pass "41 markers evaluated" || fail "$markers markers evaluated, expected 41"
finish
