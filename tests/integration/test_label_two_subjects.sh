#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Two subjects at once (issue 33 acceptance; docs/marker_sets.md, "Two subjects"): the Gait2392
# subject01 walk1 played twice through walk8.yaml's eight asynchronous cameras (a `trc:` list:
# 1.5 m apart, the second 0.7 s later; 0.3 false blobs per frame), estimated offline (--no-dds) with
# two subject models built from the same static trial (s1, s2), scored per subject against the
# simulator's truth: no name crosses subjects, >= 99.5 % of visible marker-frames right with their
# subject after the first 0.5 s, <= 0.1 % wrong, no left/right swap. About 10 s.
source "$(dirname "$0")/lib.sh"
data="$source_dir/../shared/data/static"
require_shared_data "$data/gait2392_subject01_static.trc"
require_shared_data "$data/gait2392_subject01_walk1.trc"

for s in s1 s2; do
  expect_exit 0 "model $s from the static trial" -- "$bin/panoptes_label" model \
    --static "$data/gait2392_subject01_static.trc" --markerset "$source_dir/deploy/markersets/gait2392.yaml" \
    --out "$work/$s.yaml" --subject "$s"
done

# walk8's cameras and effects; its trc section replaced by walk1 twice.
scene="$work/two.yaml"
sed -e 's/^duration: .*/duration: 5.0/' -e 's/^  false_blobs: .*/  false_blobs: 0.3/' -e '/^trc:/,$d' \
  "$source_dir/deploy/scenes/walk8.yaml" >"$scene"
cat >>"$scene" <<YAML
trc:
  - {file: $data/gait2392_subject01_walk1.trc, prefix: s1/, offset: [-0.58, -0.75, 0], turnaround: 0.5,
     start: 0.125, occlusion: {facing_angle: 100}}
  - {file: $data/gait2392_subject01_walk1.trc, prefix: s2/, offset: [-0.58, 0.75, 0], turnaround: 0.5,
     start: 0.825, occlusion: {facing_angle: 100}}
YAML
expect_exit 0 "simulate walk1 twice through eight cameras" -- "$bin/panoptes_sim" features --scene "$scene" \
  --out-dir "$work/sim"
counts=$(head -n 1 "$work/sim/truth.jsonl" | jq -r '[([.markers[].name | select(startswith("s1/"))] | length),
  ([.markers[].name | select(startswith("s2/"))] | length)] | map(tostring) | join(" ")')
read -r n1 n2 <<<"$counts"
[ "${n1:-0}" -ge 30 ] && [ "${n2:-0}" -ge 30 ] && pass "the truth has both subjects' markers ($n1, $n2 at the start)" ||
  fail "the truth's markers at the start: s1 ${n1:-?}, s2 ${n2:-?}"

expect_exit 0 "estimator_node --subjects s1,s2 offline" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --in-features "$work"/sim/cam*.jsonl --no-dds --subjects "$work/s1.yaml,$work/s2.yaml" --soft-segments Torso \
  --out-labels "$work/labels.jsonl"
grep "labels:" "$work/last.err" || true
if /usr/bin/python3 "$source_dir/tests/integration/score_labels.py" "$work/labels.jsonl" "$work/sim/truth.jsonl" \
  --by-subject --skip-s 0.5 --min-right 99.5 --max-wrong 0.1 >"$work/score.json" 2>&1; then
  pass "names right with their subject within the issue's bounds: $(cat "$work/score.json")"
else
  fail "names: $(cat "$work/score.json")"
fi
jq -e '.subject_crossings == 0 and .left_right_swaps == 0' "$work/score.json" >/dev/null &&
  pass "no name crosses subjects, no left/right swap" || fail "crossings or swaps: $(cat "$work/score.json")"
# Each subject is named at all (not one subject explaining both people's markers).
for s in s1 s2; do
  n=$(grep -o "\"subject\":\"$s\"" "$work/labels.jsonl" | wc -l)
  [ "$n" -gt 1000 ] && pass "$s names $n marker-frames" || fail "$s names only $n marker-frames"
done
finish
