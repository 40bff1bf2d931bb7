#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Articulated finger chain end to end offline (issue 21, docs/articulated.md): the hand scene's
# features -> estimator_node --bodies (type: chain) --out-chains -> tip and joint angles against
# the simulator's truth, every grab/release transition detected and none spurious.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/hand.yaml"
bodies="$source_dir/deploy/scenes/hand_bodies.yaml"

expect_exit 0 "simulate the hand scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
grep -q '"chains":\[{"angles"' "$work/sim/truth.jsonl" && pass "truth.jsonl carries the chain" ||
  fail "no chain truth in truth.jsonl"
expect_exit 0 "offline estimator with the finger chain" -- "$bin/estimator_node" \
  --calibration "$work/sim/calibration.yaml" --bodies "$bodies" --in-features "$work"/sim/c*.jsonl --no-dds \
  --out-chains "$work/chains.jsonl" --quiet
expect_stderr_contains "tracking 1 articulated chain" "the chain is loaded"
expect_stderr_contains "chains (camera frames by status): index tracking" "chain status counts in the summary"
expect_exit 0 "tip within 2 mm RMSE, angles within 2 deg, >= 95% tracked, every grab/release and none spurious" -- \
  python3 "$source_dir/tests/tools/check_chains.py" --truth "$work/sim/truth.jsonl" --chains "$work/chains.jsonl" \
  --require-tip-rmse-mm 2 --require-angle-rmse-deg 2 --require-tracked 0.95 --require-events
cat "$work/last.out"
expect_exit 2 "--out-chains without --bodies is refused" -- "$bin/estimator_node" \
  --calibration "$work/sim/calibration.yaml" --in-features "$work/sim/c0.jsonl" --no-dds --out-chains "$work/x.jsonl"
finish
