#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The side-by-side table of tests/bench/compare_builds.sh outputs (docs/benchmarks.md, issue 31).

Run in the folder holding <build>.<round> output folders: compare_builds_table.py before after [rounds]."""
import json, re, sys
rows = []
names = sys.argv[1:3] if len(sys.argv) > 2 else ["before", "after"]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 2
for w in names:
    for r in range(1, rounds + 1):
        d = f"{w}.{r}"
        det = open(f"{d}/detector.json").read()
        pan = float(re.search(r"\n  panoptes +([0-9.]+) us", det).group(1))
        ratio = float(re.search(r"ratio vs findContours\+moments +([0-9.]+)", det).group(1))
        mem = re.search(r"ratio vs memcpy +([0-9.]+)", det)
        est = open(f"{d}/estimator.json").read()
        m = re.search(r"\n +40 +\d+ +\d+ +\d+ +([0-9.]+) +([0-9.]+) +([0-9.]+)", est)
        bodies = re.search(r"bodies cost ([0-9.]+) us per frame", est)
        lat = json.load(open(f"{d}/latency.json"))
        e2e = lat["end_to_end_ms"]
        cal = json.loads([l for l in open(f"{d}/calib_studio.txt") if l.startswith("{")][0])
        ev = json.load(open(f"{d}/walk8/eval.json"))
        demo = json.load(open(f"{d}/demo.json"))
        rows.append((d, pan, ratio, mem.group(1) if mem else "-", float(m.group(1)), float(m.group(3)),
                     float(bodies.group(1)), e2e["p50"], e2e["p99"], cal["rms_2d_px"], cal["position_max_mm"],
                     ev["rmse_mm"], ev["id_switches"], ev["coverage"], demo["rmse_mm"], demo["coverage"], demo["id_switches"], demo["targets_met"]))
print("| run | detector 2048² µs (ratio vs findContours; vs memcpy) | estimator µs/observation, p99 µs | bodies µs/frame | end-to-end p50 / p99 ms | studio calibration RMS px, max position mm | walk8 RMSE mm, switches, coverage | demo RMSE mm, coverage, switches, targets |")
print("|---|---|---|---|---|---|---|---|")
for r in rows:
    print(f"| {r[0]} | {r[1]:.1f} ({r[2]:.3f}; {r[3]}) | {r[4]:.3f}, {r[5]:.1f} | {r[6]:.2f} | {r[7]:.3f} / {r[8]:.3f} | {r[9]:.4f}, {r[10]:.4f} | {r[11]:.4f}, {r[12]}, {r[13]:.6f} | {r[14]:.3f}, {r[15]:.4f}, {r[16]}, {r[17]} |")
