#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the figures a refactor must keep (issue 14) for one build's programs, into <out dir>:
# detector ratios, bench_estimator, bench_latency, the calibration studio and walk8 accuracy.
# Run it for the "before" and "after" bin folders alternately, in one session, and compare.
# Usage: compare_builds.sh <bin dir> <out dir> [source dir]   (PANOPTES_DOMAIN picks the DDS domain)
set -u
bin="$(cd "$1" && pwd)"
out="$2"
src="${3:-$(cd "$(dirname "$0")/../.." && pwd)}"
mkdir -p "$out/walk8"
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-21}"
step() { echo "compare_builds: $1" >&2; }
step "detector";    "$bin/bench_detector" --json --min-time 1 >"$out/detector.json" 2>"$out/detector.err"
step "estimator";   "$bin/bench_estimator" --no-sweep --json >"$out/estimator.json" 2>"$out/estimator.err"
step "latency";     "$bin/bench_latency" --json >"$out/latency.json" 2>"$out/latency.err"
step "calibration"; "$bin/bench_calibration" studio >"$out/calib_studio.txt" 2>&1
step "walk8"
w="$out/walk8"
"$bin/panoptes_sim" features --scene "$src/deploy/scenes/walk8.yaml" --out-dir "$w/sim" >/dev/null 2>&1
"$bin/estimator_node" --calibration "$w/sim/calibration.yaml" --in-features "$w"/sim/cam*.jsonl --no-dds \
  --out-tracks "$w/tracks.jsonl" --quiet 2>"$w/estimator.err"
"$bin/panoptes_eval" --scene "$src/deploy/scenes/walk8.yaml" --tracks "$w/tracks.jsonl" --warmup 0.5 \
  --summary-json "$w/eval.json" >"$w/eval.txt" 2>&1
sha256sum "$w/tracks.jsonl" >"$w/tracks.sha256"
step "done: $out"
