#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# panoptes_plan (docs/planner.md): a small plan end to end (calibration file, report), the plan
# evaluated again from its file gives the same figures, and the errors a user gets for bad rooms.
source "$(dirname "$0")/lib.sh"
room="$source_dir/deploy/planner/studio6x6.yaml"
plan="$bin/panoptes_plan"

# A fast room: the studio with fewer samples.
sed 's/^samples: .*/samples: {points: 400, directions: 16, seed: 3}/' "$room" >"$work/room.yaml"
expect_exit 0 "plan 4 cameras" -- "$plan" --room "$work/room.yaml" --cameras 4 --evaluations 600 --out "$work/plan.yaml" \
  --report "$work/report" --quiet
cat "$work/last.out"
for f in report.html top.png side.png history.png; do
  [ -s "$work/report/$f" ] && pass "report has $f" || fail "report lacks $f"
done
grep -q "data:image/png;base64," "$work/report/report.html" && pass "the HTML report embeds its images" ||
  fail "the HTML report does not embed its images"
[ "$(grep -c "^  - id:" "$work/plan.yaml")" -eq 4 ] && pass "the plan's calibration file lists 4 cameras" ||
  { fail "the plan's calibration file"; head -20 "$work/plan.yaml"; }
planned=$(sed -n 's/^quality \([0-9.e-]*\) m.*/\1/p' "$work/last.out")
expect_exit 0 "evaluate the planned file" -- "$plan" --room "$work/room.yaml" --evaluate "$work/plan.yaml" --remove-one
evaluated=$(sed -n 's/^quality \([0-9.e-]*\) m.*/\1/p' "$work/last.out")
[ -n "$planned" ] && [ "$planned" = "$evaluated" ] && pass "the file evaluates to the planned quality ($planned m)" ||
  fail "planned quality '$planned' but the file evaluates to '$evaluated'"
grep -q "cheapest to remove first" "$work/last.out" && pass "removal costs listed" || fail "no removal costs"
# The same seed and budget give the same plan.
"$plan" --room "$work/room.yaml" --cameras 4 --evaluations 600 --out "$work/plan2.yaml" --quiet >/dev/null
cmp -s "$work/plan.yaml" "$work/plan2.yaml" && pass "same seed, same plan" || fail "two runs with one seed differ"

# --- bad input ---------------------------------------------------------------------------------
expect_exit 0 "--help" -- "$plan" --help
grep -q "evaluations.*4000" "$work/last.out" && pass "--help shows defaults" || fail "--help lacks defaults"
grep -q "objective.*tracker_rmse" "$work/last.out" && pass "--help shows the default objective" ||
  fail "--help lacks the default objective"
expect_exit 2 "an unknown --objective" -- "$plan" --room "$work/room.yaml" --cameras 2 --objective fastest
# The room file's objective key, and --objective over it: the plan says which it minimised.
sed '$a objective: q' "$work/room.yaml" >"$work/room_q.yaml"
expect_exit 0 "plan by the room file's objective q" -- "$plan" --room "$work/room_q.yaml" --cameras 2 --evaluations 60 --quiet
grep -q "^objective q " "$work/last.out" && pass "the room file's objective is used" || fail "objective key ignored"
expect_exit 0 "--objective over the room file's" -- "$plan" --room "$work/room_q.yaml" --cameras 2 --evaluations 60 \
  --objective tracker_rmse --quiet
grep -q "^objective tracker_rmse " "$work/last.out" && pass "--objective overrides the room file" ||
  fail "--objective did not override the room file"
expect_exit 2 "no --cameras" -- "$plan" --room "$work/room.yaml"
expect_exit 2 "zero cameras" -- "$plan" --room "$work/room.yaml" --cameras 0
bad() {  # NAME SED-EXPRESSION EXPECTED-STDERR
  sed "$2" "$work/room.yaml" >"$work/$1.yaml"
  expect_exit 2 "$1" -- "$plan" --room "$work/$1.yaml" --cameras 2 --evaluations 50 --quiet
  expect_stderr_contains "$3" "$1: the message names the file and key"
}
bad no_mounts '/^mounts:/,/^lenses:/{/^mounts:/!{/^lenses:/!d}}' "no_mounts.yaml: mounts"
bad inverted_box 's/^volume: .*/volume: {min: [2, -2, 0], max: [-2, 2, 2]}/' "inverted_box.yaml: volume.max"
bad unknown_key 's/^occlusion: {planes: 64}/occlusion: {plains: 64}/' "unknown_key.yaml: occlusion.plains"
bad bad_norm 's/over_planes: rms/over_planes: median/' "bad_norm.yaml: metric.over_planes"
bad no_focal 's/focal_mm: 4.5, pixel_um: 5.3, //' "no_focal.yaml: lenses[0].focal_px"
bad bad_objective '$a objective: fastest' "bad_objective.yaml: objective"
bad negative_planes 's/^occlusion: {planes: 64}/occlusion: {planes: -3}/' "negative_planes.yaml: occlusion.planes"
bad subject_size 's/^occlusion: {planes: 64}/occlusion: {planes: 64}\nsubject: {markers: 41, size: [0.7, 0, 1.5]}/' \
  "subject_size.yaml: subject.size"
# Issue 32: --scene-out kept a trc.file of "${VAR}" only as "<template dir>/${VAR}", which no
# environment can make a path; a file that starts with a variable is written as it was.
sed "s#^  file: .*#  file: \"\${PANOPTES_PLAN_TEST_TRC}\"#" "$source_dir/deploy/scenes/walk.yaml" >"$work/env_template.yaml"
expect_exit 0 "plan with a scene template whose trc.file is \${VAR}" -- "$plan" --room "$work/room.yaml" --cameras 2 \
  --evaluations 50 --quiet --out "$work/env.cal.yaml" --scene-template "$work/env_template.yaml" --scene-out "$work/env.scene.yaml"
grep -qF 'file: ${PANOPTES_PLAN_TEST_TRC}' "$work/env.scene.yaml" && pass "--scene-out keeps trc.file \${VAR} as written" ||
  fail "--scene-out rewrote trc.file: $(grep 'file:' "$work/env.scene.yaml")"
expect_exit 0 "the written scene runs with the variable set" -- env PANOPTES_PLAN_TEST_TRC="$source_dir/tests/data/walk_41markers_100hz.trc" \
  "$bin/panoptes_sim" calibration --scene "$work/env.scene.yaml" --out "$work/env.sim.cal.yaml"
# Issue 32: only regions take a weight; the documented metric.min_triangulation_deg is read.
bad weighted_volume 's/^volume: {min: \[-2.0, -2.0, 0.0\], max: \[2.0, 2.0, 2.0\]}/volume: {min: [-2, -2, 0], max: [2, 2, 2], weight: 2}/' \
  "weighted_volume.yaml: volume.weight"
bad weighted_obstacle 's/^  - {min: \[2.3, 2.3, 0.0\], max: \[2.7, 2.7, 3.0\]}/  - {min: [2.3, 2.3, 0], max: [2.7, 2.7, 3], weight: 1}/' \
  "weighted_obstacle.yaml: obstacles[0].weight"
bad triangulation_range 's/k_cameras: 2}/k_cameras: 2, min_triangulation_deg: 95}/' \
  "triangulation_range.yaml: metric.min_triangulation_deg"
sed 's/k_cameras: 2}/k_cameras: 2, min_triangulation_deg: 0}/' "$work/room.yaml" >"$work/seed_metric.yaml"
expect_exit 0 "metric.min_triangulation_deg is accepted (0: the seed's metric)" -- \
  "$plan" --room "$work/seed_metric.yaml" --cameras 2 --evaluations 50 --quiet
# A volume no mount position can see: the lenses reach 0.5 m only.
sed 's/max_depth_m: 1[04]/max_depth_m: 0.5/g' "$work/room.yaml" >"$work/blind.yaml"
expect_exit 2 "a volume no camera can see" -- "$plan" --room "$work/blind.yaml" --cameras 2 --evaluations 50 --quiet
expect_stderr_contains "infeasible plan" "the infeasible constraint is named"
finish
