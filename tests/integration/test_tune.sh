#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# estimator_node tune (docs/recording.md, "Tune the filter"): over recorded feature JSONL of the
# tune4x scene (centroid noise 2 px, 4x the default), a short held-out-camera search writes a
# config that estimator_node --config loads, a curve CSV and a PNG; the tuned settings track
# better than the defaults; bad arguments give one-line reasons. No DDS.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/tune4x.yaml"

expect_exit 0 "simulate 4 s of tune4x features" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/rec" --duration 4
expect_exit 0 "estimator_node tune --help" -- "$bin/estimator_node" tune --help
grep -q -- "--criterion" "$work/last.out" && pass "tune --help lists --criterion" || fail "tune --help lacks --criterion"

expect_exit 0 "tune measurement noise with the held-out-camera criterion" -- "$bin/estimator_node" tune \
  --calibration "$work/rec/calibration.yaml" --in-features "$work"/rec/cam*.jsonl --params measurement_noise_px \
  --grid 5 --golden 2 --sweeps 1 --out-config "$work/tuned.yaml" --plot "$work/curve.png"
expect_stderr_contains "tune: [0] sweep 1 start" "progress names each evaluation"
[ "$(head -c 8 "$work/curve.png" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] && pass "curve PNG written" \
  || fail "no PNG at $work/curve.png"
rows=$(($(wc -l <"$work/tuned.yaml.csv") - 1))
[ "$rows" -ge 7 ] && pass "curve CSV has $rows evaluations" || fail "curve CSV has $rows rows"

expect_exit 0 "the tuned config loads with --config" -- "$bin/estimator_node" --config "$work/tuned.yaml" --print-config
sigma=$(awk '/^tracker:/ {t = 1} t && $1 == "measurement_noise_px:" {print $2; exit}' "$work/last.out")
awk -v s="$sigma" 'BEGIN {exit !(s >= 1.4 && s <= 2.8)}' && pass "tuned measurement_noise_px $sigma near the simulated 2 px" \
  || fail "tuned measurement_noise_px '$sigma' not within [1.4, 2.8]"

for run in defaults tuned; do
  config=()
  [ "$run" = tuned ] && config=(--config "$work/tuned.yaml")
  "$bin/estimator_node" "${config[@]}" --calibration "$work/rec/calibration.yaml" --in-features "$work"/rec/cam*.jsonl \
    --no-dds --out-tracks "$work/$run.jsonl" --quiet 2>/dev/null
  "$bin/panoptes_eval" --scene "$scene" --tracks "$work/$run.jsonl" --summary-json "$work/$run.json" >/dev/null
done
switches() { /usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["id_switches"])' "$1"; }
coverage() { /usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["coverage"])' "$1"; }
echo "defaults: $(switches "$work/defaults.json") ID switches, coverage $(coverage "$work/defaults.json"); tuned: $(switches "$work/tuned.json") switches, coverage $(coverage "$work/tuned.json")"
[ "$(switches "$work/tuned.json")" -lt "$(switches "$work/defaults.json")" ] && pass "tuned settings switch IDs less than the defaults" \
  || fail "tuned settings no better than the defaults in ID switches"

# --- bad arguments: one line naming the problem, exit 2 ----------------------------------------
expect_exit 2 "unknown parameter" -- "$bin/estimator_node" tune --calibration "$work/rec/calibration.yaml" \
  --in-features "$work/rec/cam0.jsonl" --params process_nosie --out-config "$work/x.yaml"
expect_stderr_contains "process_nosie" "the unknown parameter is named"
expect_exit 2 "truth criterion without a scene" -- "$bin/estimator_node" tune --calibration "$work/rec/calibration.yaml" \
  --in-features "$work"/rec/cam*.jsonl --criterion truth --out-config "$work/x.yaml"
expect_stderr_contains "--scene" "the missing --scene is named"
expect_exit 2 "missing features file" -- "$bin/estimator_node" tune --calibration "$work/rec/calibration.yaml" \
  --in-features "$work/none.jsonl" --out-config "$work/x.yaml"
expect_stderr_contains "none.jsonl" "the missing features file is named"
expect_exit 2 "held-out criterion with two cameras" -- "$bin/estimator_node" tune --calibration "$work/rec/calibration.yaml" \
  --in-features "$work/rec/cam0.jsonl" "$work/rec/cam1.jsonl" --out-config "$work/x.yaml"
expect_stderr_contains "at least 3" "the reason is given"
# Malformed feature lines are counted, skipped and named; the tuning still runs.
{ head -200 "$work/rec/cam0.jsonl"; echo 'not json'; echo '{"camera_id": "cam0"}'; } >"$work/mangled.jsonl"
expect_exit 0 "malformed feature lines are skipped" -- "$bin/estimator_node" tune --calibration "$work/rec/calibration.yaml" \
  --in-features "$work/mangled.jsonl" "$work"/rec/cam[123].jsonl --params measurement_noise_px --grid 2 --golden 0 \
  --sweeps 1 --out-config "$work/x.yaml"
expect_stderr_contains "mangled.jsonl:201" "the first malformed line is named with file and line"
expect_stderr_contains "2 malformed lines skipped" "the malformed lines are counted"
finish
