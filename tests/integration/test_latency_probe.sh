#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Latency probes (issue 7, docs/protocol.md "Latency probes"): bench_latency runs camera_node and
# estimator_node with --latency-probe; every probe must come back as an echo of a BodyPose's size,
# and every traced frame's BodyPose must be found. Speed is not asserted (docs/benchmarks.md has
# the figures); this checks that the measurement works. Skipped (77) without the benchmarks.
source "$(dirname "$0")/lib.sh"
if [ ! -x "$bin/bench_latency" ]; then
  echo "bench_latency not built (-DPANOPTES_BUILD_BENCHMARKS=ON): skipped"
  exit 77
fi

expect_exit 0 "bench_latency runs the pipeline with probes" -- "$bin/bench_latency" --json --duration 2 \
  --warmup 1 --domain "$PANOPTES_DOMAIN" --log-dir "$work/run" --samples "$work/samples.jsonl"
cp "$work/last.out" "$work/result.json"
expect_stderr_contains "measuring" "progress on stderr"
python3 - "$work/result.json" "$work/samples.jsonl" <<'PY' && pass "probes echoed, poses tied to their frames, stamps in order" || fail "latency probe results: $(head -c 600 "$work/result.json")"
import json, sys
result = json.load(open(sys.argv[1]))
frames = 2 * 4 * 240  # 2 s, 4 cameras at 240 Hz
floor = result["dds_floor_ms"]["two_hops_plus_detection"]
end_to_end = result["end_to_end_ms"]
assert floor["n"] >= 0.9 * frames, f"echoes {floor['n']} of {frames} probes"
# A frame that arrives late is replayed into the state, and the pose published then belongs to a
# newer frame: under stalls fewer frames have a pose of their own. Stop 79 on this machine, alone
# and idle: 1421-1498 of 1920 (74-78 %) in 5 of 9 runs, with the JSON code before and after that
# stop's change alike (latency p99 ~310 ms, clock-sync round trips up to 330 ms: the processes
# stalled), 80 % or more in the others. What this test checks is that the measurement works.
assert end_to_end["n"] >= 0.6 * frames, f"{end_to_end['n']} frames with a pose of {frames}"
assert result["poses_unmatched"] <= 0.02 * end_to_end["n"], result["poses_unmatched"]
assert 0 < floor["p50"] and 0 < end_to_end["p50"] and result["ratio_vs_dds_floor_p99"] > 0
for line in open(sys.argv[2]):
    s = json.loads(line)
    # The estimator's own stamps are on one clock: strictly in order.
    stamps = [s["received_ns"], s["dequeued_ns"], s["updated_ns"], s["poses_published_ns"]]
    assert stamps == sorted(stamps), s
    # The camera clock is synchronised to this host's within ~0.1 ms, so stamps taken in different
    # processes are compared with that margin (CI once saw reception 10 us "before" arrival).
    assert s["received_ns"] >= s["arrival_ns"] - 200_000, s
    assert s["feature_publish_ns"] - s["arrival_ns"] >= s["processing_ns"] - 200_000, s
    assert s["pose_received_ns"] >= s["poses_published_ns"] - 200_000, s
PY
grep -q "benchmark aid: echoing latency probes" "$work/run/estimator_node.log" && pass "estimator_node says it echoes" ||
  fail "estimator_node log lacks the probe line"
finish
