#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Names after a long occlusion (issue 33: "every name returns within 100 ms of its marker
# reappearing"; docs/marker_sets.md, "Names after a long occlusion"): the Gait2392 subject01 walk1
# through walk8.yaml's eight asynchronous cameras (0.3 false blobs per frame) with six markers hidden
# from every camera for 0.5-1.0 s each (trc.hide), longer than the tracker keeps a coasting track
# (300 ms), so each comes back under a new track: on rigid segments (L.Shank.Front, R.ASIS,
# Top.Head, R.Heel) and on two-marker ones (R.Elbow, L.Wrist.Lat). Estimated offline (--no-dds) with
# the model from the static trial, three seeds: every hidden marker is named within 100 ms of its
# first track after the occlusion, >= 99.5 % of the visible marker-frames right and <= 0.1 % wrong
# after the first 0.5 s, no left/right swap. Before the fixes this test came with, seed 3 named
# L.Shank.Upper "L.Shank.Front" for 3.7 s (1.35 % wrong; the coasting track had taken the
# neighbour's blobs and the merge kept it as the older). Since stop 93 the tracker gives some such
# markers their old track back (reacquisition by neighbours, docs/estimator.md): the three seeds run
# with it off (tracker.reacquire_neighbours_m: 0), so that the markers still come back under new
# tracks, which is what this test is for; seed 8 runs once more with the default, where the names
# must be as right and some hidden markers must have taken their old tracks back. About 25 s.
source "$(dirname "$0")/lib.sh"
data="$source_dir/../shared/data/static"
require_shared_data "$data/gait2392_subject01_static.trc"
require_shared_data "$data/gait2392_subject01_walk1.trc"

expect_exit 0 "model from the static trial" -- "$bin/panoptes_label" model \
  --static "$data/gait2392_subject01_static.trc" --markerset "$source_dir/deploy/markersets/gait2392.yaml" \
  --out "$work/s1.yaml" --subject s1

# marker from to (scene s)
hides=("R.Elbow 1.0 1.6" "L.Shank.Front 2.0 2.8" "Top.Head 3.0 3.5" "R.ASIS 4.0 5.0" "L.Wrist.Lat 5.2 5.8"
  "R.Heel 6.0 6.7")
hide_yaml="  hide:"
hidden_args=()
for h in "${hides[@]}"; do
  read -r marker from to <<<"$h"
  hide_yaml+=$'\n'"    - {marker: $marker, from: $from, to: $to}"
  hidden_args+=(--hidden "$marker:$to")
done

for seed in 8 3 1; do
  dir="$work/seed$seed"
  mkdir -p "$dir"
  # walk1 through walk8's cameras, the hidden markers added to its trc section (the file's last).
  walk1_in_walk8 "$dir/scene.yaml" 's/^duration: .*/duration: 7.5/' "s/^seed: .*/seed: $seed/"
  printf '%s\n' "$hide_yaml" >>"$dir/scene.yaml"
  expect_exit 0 "seed $seed: simulate walk1 with six markers hidden for a while" -- "$bin/panoptes_sim" features \
    --scene "$dir/scene.yaml" --out-dir "$dir/sim"
  label_offline "$dir/sim" "$work/s1.yaml" "$dir/labels.jsonl" \
    "seed $seed: estimator_node --subjects offline, reacquisition by neighbours off" --config "$source_dir/tests/accuracy/reacquire_neighbours_off.yaml"
  if /usr/bin/python3 "$source_dir/tests/integration/score_labels.py" "$dir/labels.jsonl" "$dir/sim/truth.jsonl" \
    --skip-s 0.5 --min-right 99.5 --max-wrong 0.1 "${hidden_args[@]}" --max-reappear-ms 100 --explain 3 \
    >"$dir/score.json" 2>"$dir/score.err"; then
    pass "seed $seed: every hidden marker named within 100 ms of reappearing, names within the issue's bounds: $(cat "$dir/score.json")"
  else
    fail "seed $seed: $(cat "$dir/score.json" "$dir/score.err")"
  fi
  # The occlusions replaced tracks (a new track on a marker named before): what the test is for.
  [ -s "$dir/score.json" ] && jq -e '.left_right_swaps == 0 and .returns >= 4' "$dir/score.json" >/dev/null &&
    pass "seed $seed: no left/right swap; $(jq .returns "$dir/score.json") markers came back under a new track" ||
    fail "seed $seed: swaps or too few new tracks on known markers: $(cat "$dir/score.json")"
done

# The default: hidden markers may come back under their old tracks, and keep their names.
dir="$work/seed8"
label_offline "$dir/sim" "$work/s1.yaml" "$dir/labels_default.jsonl" "seed 8: estimator_node --subjects offline (defaults)"
reacquired=$(grep -o "reacquired [0-9]* ([0-9]* by neighbours)" "$work/last.err" | grep -o "([0-9]*" | tr -d '(')
if /usr/bin/python3 "$source_dir/tests/integration/score_labels.py" "$dir/labels_default.jsonl" "$dir/sim/truth.jsonl" \
  --skip-s 0.5 --min-right 99.5 --max-wrong 0.1 >"$dir/score_default.json" 2>"$dir/score_default.err" &&
  jq -e '.left_right_swaps == 0' "$dir/score_default.json" >/dev/null && [ "${reacquired:-0}" -ge 1 ]; then
  pass "seed 8, defaults: ${reacquired} tracks reacquired by neighbours, names within the issue's bounds: $(cat "$dir/score_default.json")"
else
  fail "seed 8, defaults: reacquired by neighbours ${reacquired:-none}; $(cat "$dir/score_default.json" "$dir/score_default.err")"
fi
finish
