#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A subject model trained from a labelled dynamic trial instead of a static one (issue 33
# acceptance; docs/marker_sets.md, "From a labelled dynamic trial"): panoptes_label model
# --labelled on the first half of Gait2392 subject01's walk1 (frames 0-74), then the walk's second
# half (from 1.25 s, forwards to the end and back: pingpong with the scene's 0.5 s turnaround) through walk8.yaml's eight asynchronous
# cameras with 0.3 false blobs per frame, estimated offline (--no-dds --subjects) and scored against
# the simulator's truth: >= 99 % of visible marker-frames right after the first 0.5 s, <= 0.2 %
# wrong, no left/right swap. About 10 s.
source "$(dirname "$0")/lib.sh"
data="$source_dir/../shared/data/static"
require_shared_data "$data/gait2392_subject01_walk1.trc"

expect_exit 0 "model from the walk's first half (--labelled --frames :75)" -- "$bin/panoptes_label" model \
  --labelled "$data/gait2392_subject01_walk1.trc" --frames :75 \
  --markerset "$source_dir/deploy/markersets/gait2392.yaml" --out "$work/s1.yaml" --subject s1
grep -q "kind: labelled" "$work/s1.yaml" && pass "the model records its labelled trial" ||
  fail "the model's trial: $(grep -m1 'trial:' "$work/s1.yaml")"

# The second half only: 1.25 s in, to the end (2.5 s) and back over the 2.5 s scene.
scene="$work/half.yaml"
walk1_in_walk8 "$scene" 's/^duration: .*/duration: 2.5/' 's/^  start: .*/  start: 1.25/'
expect_exit 0 "simulate the walk's second half through eight cameras" -- "$bin/panoptes_sim" features \
  --scene "$scene" --out-dir "$work/sim"
label_offline "$work/sim" "$work/s1.yaml" "$work/labels.jsonl" "estimator_node --subjects (the dynamic model) offline"
if /usr/bin/python3 "$source_dir/tests/integration/score_labels.py" "$work/labels.jsonl" "$work/sim/truth.jsonl" \
  --skip-s 0.5 --min-right 99 --max-wrong 0.2 >"$work/score.json" 2>&1; then
  pass "second half named by the first half's model within the issue's bounds: $(cat "$work/score.json")"
else
  fail "names: $(cat "$work/score.json")"
fi
jq -e '.left_right_swaps == 0' "$work/score.json" >/dev/null && pass "no left/right swap" ||
  fail "left/right swaps: $(cat "$work/score.json")"
finish
