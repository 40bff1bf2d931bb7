#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Articulated chains in the operator console (docs/console.md, "Chains"; docs/articulated.md): the
# hand scene (test_chains.sh's, 80 s of it) replayed live by four camera_nodes into estimator_node --bodies
# hand_bodies.yaml --out-chains, panoptes_console, and Debian's chromium driven by playwright-core
# (tools/console/web/test/console_chains_test.mjs). The browser checks that the chain is
# listed with its figures, that its tip is drawn where the published tip projects, and that a
# grab turns it magenta; this script checks that every chain state the page showed is one the
# estimator wrote to its Chain JSONL (same stamp: same tip and predicted tip, to the page's 0.1 mm
# rounding). Screenshots go to $PANOPTES_CONSOLE_SHOTS (docs/).
source "$(dirname "$0")/lib.sh"
require_browser
scene="$source_dir/deploy/scenes/hand.yaml"
shots="${PANOPTES_CONSOLE_SHOTS:-$work/shots}"
mkdir -p "$shots"
# 80 s of the scene (its script repeats): on a loaded machine the browser may take a while to start
# (a fresh-clone run beside other tests saw chromium load the page 18 s into the replay and the
# checks still running at 60 s). Unloaded, the browser checks take about 12 s.
"$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 80 >/dev/null 2>&1 ||
  { fail "simulate the hand scene"; finish; }

"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$source_dir/deploy/scenes/hand_bodies.yaml" \
  --duration 90 --status-period 1 --out-chains "$work/live.jsonl" >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
start_console chains
epoch=$(( ($(date +%s) + 2) * 1000000000 ))
replay_cameras "$epoch" 80 c0 c1 c2 c3

start=$(date +%s)
timeout 100 node "$web/test/console_chains_test.mjs" --url "$url" --out "$work/browser.json" --shots "$shots" |
  tee "$work/browser.out"
rc=${PIPESTATUS[0]}
[ "$rc" -eq 0 ] && pass "browser checks ($(( $(date +%s) - start )) s)" || fail "browser checks (exit $rc)"

kill -INT "$estimator" 2>/dev/null
timeout 10 tail -s 0.05 --pid="$estimator" -f /dev/null
/usr/bin/python3 - "$work" <<'PY' || failures=$((failures + 1))
import bisect, json, sys
work = sys.argv[1]
samples = json.load(open(f"{work}/browser.json"))["samples"]
records = [r for r in map(json.loads, open(f"{work}/live.jsonl"))
           if r["type"] == "chain" and r["chain"] == "index" and r["status"] == "tracking"]
stamps = [r["stamp_ns"] for r in records]
matched, worst = 0, 0.0
for s in samples:
    # The page holds stamps as JavaScript numbers (exact to 256 ns at 1.7e18); frames are >= 2.5 ms apart.
    i = bisect.bisect_left(stamps, s["stamp_ns"] - 1000)
    if i == len(stamps) or abs(stamps[i] - s["stamp_ns"]) > 1000:
        continue
    r = records[i]
    matched += 1
    for key in ("tip", "predicted_tip"):
        worst = max(worst, max(abs(a - b) for a, b in zip(r[key], s[key])))
    if s["horizon_ms"] * 1e6 != r["prediction_horizon_ns"]:
        worst = float("inf")
ok = len(samples) >= 10 and matched == len(samples) and worst <= 0.00005 + 1e-9
print(("PASS: " if ok else "FAIL: ") +
      f"the page's chain states are the estimator's Chain JSONL records: {matched} of {len(samples)} found by stamp, "
      f"tip and predicted tip within {worst * 1e3:.3f} mm (0.05 mm rounding), horizon 80 ms")
sys.exit(0 if ok else 1)
PY
finish
