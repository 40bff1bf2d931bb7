#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The planner against our own system (issue 19, item 4; docs/planner.md, "Validation"): for several
# layouts of the same room (planned, rule-of-thumb rings, all on one wall, clustered in a corner)
# the real walking motion (41 markers, self-occlusion by the body) is simulated through the
# tracker; the planner's predicted P(>= 2 cameras see a point), uncertainty and tracker RMSE are
# compared by rank with the measured share of marker-time seen by >= 2 cameras and the tracks' RMSE.
source "$(dirname "$0")/lib.sh"
room="$source_dir/deploy/planner/walk_room.yaml"
plan="$bin/panoptes_plan"
duration=4

# The walk of walk8.yaml without its cameras: the template every layout's scene is made from.
sed '/^cameras:/,/^trc:/{/^trc:/!d}' "$source_dir/deploy/scenes/walk8.yaml" |
  sed "s#^trc:#cameras:\n  - {id: t, rate: 100}\n\ntrc:#; s#file: ../../tests/data#file: $source_dir/tests/data#" \
    >"$work/template.yaml"

# layout NAME "x y z; x y z; ...": cameras at those positions aimed at the subject's middle, as a
# scene; its calibration file comes from panoptes_sim.
layout() {
  local name="$1" positions="$2" i=0 eye
  {
    sed '/^cameras:/,$d' "$work/template.yaml"
    echo "cameras:"
    IFS=';' read -ra eyes <<<"$positions"
    for eye in "${eyes[@]}"; do
      read -r x y z <<<"$eye"
      echo "  - {id: cam$i, K: [1000, 1000, 639.5, 511.5], look_at: {eye: [$x, $y, $z], target: [0.1, 0.0, 0.8]}, rate: 100, phase: 0.00$i}"
      i=$((i + 1))
    done
    sed -n '/^trc:/,$p' "$work/template.yaml"
  } >"$work/$name.scene.yaml"
  "$bin/panoptes_sim" calibration --scene "$work/$name.scene.yaml" --out "$work/$name.cal.yaml" >/dev/null ||
    fail "$name: panoptes_sim calibration"
}

ring() {  # N RX RY Z: N cameras on an ellipse
  /usr/bin/python3 -c "import math;n=$1;print(';'.join('%.3f %.3f $4'%($2*math.cos(2*math.pi*k/n+0.3),$3*math.sin(2*math.pi*k/n+0.3)) for k in range(n)))"
}
layout ring8 "$(ring 8 3.9 2.9 2.5)"
layout ring6 "$(ring 6 3.9 2.9 2.5)"
layout ring4 "$(ring 4 3.9 2.9 2.5)"
layout ring3 "$(ring 3 3.9 2.9 2.5)"
layout wall6 "-3.5 2.95 2.2; -2.1 2.95 2.7; -0.7 2.95 2.2; 0.7 2.95 2.7; 2.1 2.95 2.2; 3.5 2.95 2.7"
layout corner6 "3.9 2.9 2.0; 3.5 2.9 2.4; 3.9 2.5 2.8; 3.1 2.9 2.8; 3.9 2.1 2.4; 3.9 2.9 2.6"
layout pair "3.9 0.2 2.4; -3.9 -0.2 2.4"

# The planner's own layout of 4 cameras, written as a scene from the template (with 6 or more
# cameras the rings already see everything by two): with the default objective (tracker_rmse),
# and with the seed's q for the comparison that made tracker_rmse the default (docs/planner.md,
# "Objectives"). The q plan is judged apart: it is not one of the ranked layouts.
expect_exit 0 "plan 4 cameras for the walk" -- "$plan" --room "$room" --cameras 4 --evaluations 4000 --quiet \
  --out "$work/planned.cal.yaml" --scene-template "$work/template.yaml" --scene-out "$work/planned.scene.yaml"
grep -q "^objective tracker_rmse " "$work/last.out" && pass "the default objective is tracker_rmse" ||
  fail "the default objective is not tracker_rmse: $(grep '^objective' "$work/last.out")"
expect_exit 0 "plan 4 cameras for the walk by q" -- "$plan" --room "$room" --cameras 4 --evaluations 4000 --quiet \
  --objective q --out "$work/planned_q.cal.yaml" --scene-template "$work/template.yaml" \
  --scene-out "$work/planned_q.scene.yaml"

results="$work/results.txt"
: >"$results"
for name in planned ring8 ring6 ring4 ring3 wall6 corner6 pair planned_q; do
  "$plan" --room "$room" --evaluate "$work/$name.cal.yaml" >"$work/$name.plan.out" 2>&1 ||
    { fail "$name: evaluate"; cat "$work/$name.plan.out"; continue; }
  predicted_p=$(sed -n 's/.*see a point) \([0-9.]*\)$/\1/p' "$work/$name.plan.out")
  predicted_u=$(sed -n 's/^uncertainty where .* see a point \([0-9.e-]*\) m$/\1/p' "$work/$name.plan.out")
  predicted_q=$(sed -n 's/^quality \([0-9.e-]*\) m.*/\1/p' "$work/$name.plan.out")
  predicted_r=$(sed -n 's/^predicted tracker RMSE \([0-9.e-]*\) m, with two-view ambiguity \([0-9.e-]*\) m$/\1 \2/p' "$work/$name.plan.out")
  predicted_c=$(sed -n 's/.*confirmable \([0-9.]*\) of .*/\1/p' "$work/$name.plan.out")
  rm -rf "$work/$name.sim"
  "$bin/panoptes_sim" features --scene "$work/$name.scene.yaml" --out-dir "$work/$name.sim" --duration "$duration" \
    >/dev/null 2>&1 || { fail "$name: simulate"; continue; }
  "$bin/estimator_node" --calibration "$work/$name.sim/calibration.yaml" --in-features $(ls "$work/$name.sim"/*.jsonl | grep -v truth.jsonl) \
    --no-dds --out-tracks "$work/$name.tracks.jsonl" --quiet 2>/dev/null || { fail "$name: estimator"; continue; }
  "$bin/panoptes_eval" --scene "$work/$name.scene.yaml" --tracks "$work/$name.tracks.jsonl" \
    --summary-json "$work/$name.eval.json" >/dev/null 2>&1 || { fail "$name: eval"; continue; }
  echo "$name $predicted_p $predicted_u $predicted_q $predicted_r $predicted_c $work/$name.eval.json" >>"$results"
done

/usr/bin/python3 - "$results" <<'PY' >"$work/validation.out"
import json, sys
import numpy as np
rows = []
for line in open(sys.argv[1]):
    name, p, u, q, r, ra, c, path = line.split()
    e = json.load(open(path))
    steps = sum(m["steps"] for m in e["markers"])
    trackable = sum(m["trackable"] for m in e["markers"])
    rows.append((name, float(p), float(u), trackable / steps, e["rmse_mm"], e["coverage"], float(q),
                 1000 * float(r), 1000 * float(ra), float(c)))
by = {r[0]: r for r in rows}
rows = [r for r in rows if r[0] != "planned_q"]  # the ranked layouts
def rank(v):
    r = np.empty(len(v)); r[np.argsort(v, kind="stable")] = np.arange(len(v)); return r
def spearman(a, b):
    return float(np.corrcoef(rank(np.array(a)), rank(np.array(b)))[0, 1])
print("%-8s %10s %12s %10s %9s %9s %10s %9s %9s %9s" % ("layout", "pred P>=2", "pred U m", "meas >=2", "RMSE mm",
      "coverage", "quality m", "pred RMSE", "+ambig.", "confirm."))
for r in rows:
    print("%-8s %10.4f %12.5g %10.4f %9.3f %9.4f %10.4g %9.3f %9.3f %9.4f" % r)
print("spearman_q %.3f" % spearman([r[6] for r in rows], [r[4] for r in rows]))
print("spearman_p %.3f" % spearman([r[1] for r in rows], [r[3] for r in rows]))
print("spearman_u %.3f" % spearman([r[2] for r in rows], [r[4] for r in rows]))
print("spearman_r %.3f" % spearman([r[7] for r in rows], [r[4] for r in rows]))
print("spearman_ra %.3f" % spearman([r[8] for r in rows], [r[4] for r in rows]))
print("spearman_c %.3f" % spearman([r[9] for r in rows], [r[5] for r in rows]))
if "planned_q" in by:
    print("%-8s %10.4f %12.5g %10.4f %9.3f %9.4f %10.4g %9.3f %9.3f %9.4f (not ranked)" % by["planned_q"])
print("planned_vs_ring4 %.4f %.4f" % (by["planned"][3], by["ring4"][3]))
print("planned_vs_ring4_tracked %.4f %.4f" % (by["planned"][5], by["ring4"][5]))
print("planned_vs_ring4_rmse %.3f %.3f" % (by["planned"][4], by["ring4"][4]))
if "planned_q" in by:
    print("planned_vs_planned_q_rmse %.3f %.3f" % (by["planned"][4], by["planned_q"][4]))
    print("planned_vs_planned_q_two %.4f %.4f" % (by["planned"][3], by["planned_q"][3]))
PY
cat "$work/validation.out"
rows=$(grep -vc "^planned_q " "$results")
[ "$rows" -ge 6 ] && pass "$rows layouts simulated and judged" || fail "only $rows layouts judged"
sp=$(sed -n 's/^spearman_p //p' "$work/validation.out")
su=$(sed -n 's/^spearman_u //p' "$work/validation.out")
awk -v s="$sp" 'BEGIN { exit !(s ~ /^-?[0-9.]+$/ && s >= 0.9) }' && pass "rank correlation of predicted and measured >=2-camera share: $sp" ||
  fail "rank correlation of predicted and measured >=2-camera share: $sp < 0.9"
# Goal (issue 19): >= 0.9 between predicted uncertainty and measured RMSE. The planner's predicted
# tracker RMSE (triangulation where >= 2 cameras see, the coasting error for the reported part of
# one-camera time) ranks the layouts at 0.93-0.95 over the scene seeds 8, 9, 10 (2026-11-27,
# docs/planner.md; 0.905 with the per-camera search's plan); the seed's quality q, which prices
# resolution and occlusion but not two-view time, at 0.83-0.95, guarded lower so that a
# regression shows.
sr=$(sed -n 's/^spearman_r //p' "$work/validation.out")
awk -v s="$sr" 'BEGIN { exit !(s ~ /^-?[0-9.]+$/ && s >= 0.9) }' &&
  pass "rank correlation of the predicted tracker RMSE and the measured RMSE: $sr" ||
  fail "rank correlation of the predicted tracker RMSE and the measured RMSE: $sr < 0.9"
sq=$(sed -n 's/^spearman_q //p' "$work/validation.out")
awk -v s="$sq" 'BEGIN { exit !(s ~ /^-?[0-9.]+$/ && s >= 0.8) }' &&
  pass "rank correlation of the predicted quality and the measured RMSE: $sq (uncertainty where seen: $su)" ||
  fail "rank correlation of the predicted quality and the measured RMSE: $sq < 0.8"
# compare KEY CONDITION TEXT: the two figures a and b on the line "KEY a b" of validation.out
# satisfy the awk CONDITION.
compare() {
  local a b
  read -r _ a b < <(grep "^$1 " "$work/validation.out")
  if awk -v a="$a" -v b="$b" "BEGIN { exit !(a != \"\" && b != \"\" && ($2)) }"; then
    pass "$3 ($a vs $b)"
  else
    fail "NOT $3 ($a vs $b)"
  fi
}
compare planned_vs_ring4 "a + 0 > b + 0" "the planned layout covers more marker-time with >= 2 cameras than the ring of 4"
compare planned_vs_ring4_tracked "a + 0 > b + 0" "the planned layout's tracks cover more of the marker-time than the ring of 4's"
# Why tracker_rmse is the default: its plan tracks with a lower measured RMSE than q's plan and sees
# as much by >= 2 cameras (seeds 1-3: 1.344/1.349/1.417 mm against 1.633/1.482/1.687 mm, all
# 1.0000 seen by two; docs/planner.md, "Objectives").
compare planned_vs_planned_q_rmse "a + 0 < b + 0" "the tracker_rmse plan tracks with a lower RMSE (mm) than the q plan"
compare planned_vs_planned_q_two "a + 0 >= b + 0" "the tracker_rmse plan sees as much by >= 2 cameras as the q plan"
# Against the ring of 4 the plan does NOT reach the goal (RMSE at most the ring's): 1.344 vs
# 1.061 mm on 2026-11-27: the ring sees 2.5% of the marker-time by fewer than two cameras and is
# more precise where it sees; the objective takes the coverage (docs/planner.md, "Not yet done").
# This bound only guards against a regression: 1.3x the ring's, measured 1.27x, until stop 88's
# publication limits (12 mm, 2 px; docs/estimator.md, "Publication limits for the edges") lowered
# both RMSEs, the ring's more: 1.380 -> 1.363 mm and 1.065 -> 1.038 mm, 1.296x -> 1.314x (the same
# binary with and without the new limits in --config, seed 8). Now 1.35x.
compare planned_vs_ring4_rmse "a + 0 <= 1.35 * b" \
  "the planned layout's RMSE (mm) is within 1.35x the ring of 4's (a regression guard; the goal, <= 1x, is not met)"
finish
