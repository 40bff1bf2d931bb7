#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# How long a late frame matters to a zero-wait estimator (docs/estimator.md, "How long a
# late frame matters"). The walk8 scene is simulated in order and with 10% of frames late by
# delays drawn uniformly in each range below (the same frames are late in every run: the late draw
# does not depend on the range). Each late run is estimated offline in arrival order with the
# estimator's defaults (zero wait, replays from checkpoints) and scored against the truth. In the
# last row the late frames come after the rewind horizon (500 ms), so every one is dropped.
# Prints one row per delay range: RMSE and its ratio to the in-order RMSE.
#   tests/bench/bench_late_delay.sh <build dir> [late fraction] [estimator options...]
set -euo pipefail
build="${1:?build directory}"
fraction="${2:-0.1}"
shift $(($# >= 2 ? 2 : 1))
root=$(cd "$(dirname "$0")/../.." && pwd)
bin="$build/bin"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

trc="$root/tests/data/walk_41markers_100hz.trc"
sed -e "s#file: .*walk_41markers_100hz.trc#file: $trc#" "$root/deploy/scenes/walk8.yaml" >"$work/inorder.yaml"

rmse() { python3 -c "import json,sys; print('%.4f' % json.load(open(sys.argv[1]))['rmse_mm'])" "$1"; }

run() {  # NAME SCENE [estimator options]: simulate, estimate in arrival order, score; prints the RMSE
  local name="$1" scene="$2"
  shift 2
  "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/$name" >/dev/null
  "$bin/estimator_node" --calibration "$work/$name/calibration.yaml" --in-features "$work/$name"/cam*.jsonl \
    --no-dds --replay-arrival --out-tracks "$work/$name.jsonl" --quiet "$@" 2>/dev/null
  "$bin/panoptes_eval" --scene "$scene" --tracks "$work/$name.jsonl" --warmup 0.5 \
    --summary-json "$work/$name.json" >/dev/null
  rmse "$work/$name.json"
}

late_scene() {  # MIN MAX (seconds) -> scene file with that late-delay range
  local file="$work/late_$1_$2.yaml"
  sed -e "s/^  late_fraction: 0.0\$/  late_fraction: $fraction\n  late_delay: [$1, $2]/" "$work/inorder.yaml" >"$file"
  grep -q "late_delay: \[$1, $2\]" "$file" || { echo "could not write the late scene" >&2; exit 1; }
  echo "$file"
}

base=$(run inorder "$work/inorder.yaml" "$@")
echo "walk8, ${fraction} of frames late; estimator options: ${*:-defaults}"
echo "in order: RMSE $base mm"
printf '%-24s %-10s %s\n' "late by (ms)" "RMSE mm" "vs in order"
row() {  # LABEL RMSE
  printf '%-24s %-10s %s\n' "$1" "$2" "$(python3 -c "import sys; print('%+.2f%%' % (100 * (float(sys.argv[1]) / float(sys.argv[2]) - 1)))" "$2" "$base")"
}
for range in "0.0005 0.001" "0.001 0.003" "0.003 0.005" "0.005 0.010" "0.010 0.020" "0.020 0.030" "0.005 0.030"; do
  read -r lo hi <<<"$range"
  scene=$(late_scene "$lo" "$hi")
  row "$(python3 -c "import sys; print('%g-%g' % (1e3 * float(sys.argv[1]), 1e3 * float(sys.argv[2])))" "$lo" "$hi")" \
    "$(run "late_${lo}_${hi}" "$scene" "$@")"
done
row "1000-2000 (dropped)" "$(run dropped "$(late_scene 1.0 2.0)" "$@")"
