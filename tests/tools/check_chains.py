#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# Scores estimator_node --out-chains (Chain JSONL, docs/articulated.md) against panoptes_sim's
# truth.jsonl: tip and joint-angle RMSE of the tracking records after a warm-up, the predicted
# tip's RMSE against the truth prediction_horizon_ns later (records written before the JSONL had a
# predicted tip are scored without it), the fraction tracked, and grab/release events matched one to one to the truth's threshold crossings (the
# same hysteresis as the estimator's GrabDetector). Exit 1 when a --require-* bound fails.
import argparse
import bisect
import json
import math
import sys


def load_truth(path, chain):
    stamps, tips, angles = [], [], []
    for line in open(path):
        record = json.loads(line)
        for c in record.get("chains", []):
            if c["name"] == chain:
                stamps.append(record["stamp_ns"])
                tips.append(c["tip"])
                angles.append(c["angles"])
    if not stamps:
        sys.exit(f"{path}: no truth for chain '{chain}'")
    return stamps, tips, angles


def interpolate(stamps, values, stamp):
    i = min(max(bisect.bisect_left(stamps, stamp), 1), len(stamps) - 1)
    w = (stamp - stamps[i - 1]) / (stamps[i] - stamps[i - 1])
    w = min(max(w, 0.0), 1.0)
    return [a + w * (b - a) for a, b in zip(values[i - 1], values[i])]


def truth_transitions(stamps, angles, grab_rad, release_rad):
    events, grabbing = [], False
    for stamp, a in zip(stamps, angles):
        bend = sum(a)
        if not grabbing and bend > grab_rad:
            grabbing = True
            events.append(("grab", stamp))
        elif grabbing and bend < release_rad:
            grabbing = False
            events.append(("release", stamp))
    return events


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--truth", required=True)
    parser.add_argument("--chains", required=True)
    parser.add_argument("--chain", default="index")
    parser.add_argument("--warmup", type=float, default=0.5, help="s after the first record")
    parser.add_argument("--grab-rad", type=float, default=1.6)
    parser.add_argument("--release-rad", type=float, default=1.0)
    parser.add_argument("--event-window", type=float, default=0.1, help="s between an event and its truth")
    parser.add_argument("--require-tip-rmse-mm", type=float)
    parser.add_argument("--require-angle-rmse-deg", type=float)
    parser.add_argument("--require-predicted-rmse-mm", type=float,
                        help="predicted tip against the truth prediction_horizon_ns later")
    parser.add_argument("--require-tracked", type=float)
    parser.add_argument("--require-events", action="store_true", help="every transition detected, none spurious")
    args = parser.parse_args()

    stamps, tips, angles = load_truth(args.truth, args.chain)
    records, events = [], []
    for line in open(args.chains):
        r = json.loads(line)
        if r.get("chain") != args.chain:
            continue
        (records if r["type"] == "chain" else events).append(r)
    if not records:
        sys.exit(f"{args.chains}: no records of chain '{args.chain}'")
    start = records[0]["stamp_ns"] + int(args.warmup * 1e9)
    scored = [r for r in records if r["stamp_ns"] >= start]
    tracked = [r for r in scored if r["status"] == "tracking"]
    tip_sq, tip_max, angle_sq, angle_n = 0.0, 0.0, 0.0, 0
    for r in tracked:
        tip = interpolate(stamps, tips, r["stamp_ns"])
        error = math.dist(tip, r["tip"])
        tip_sq += error * error
        tip_max = max(tip_max, error)
        for estimated, true in zip(r["angles"], interpolate(stamps, angles, r["stamp_ns"])):
            angle_sq += (estimated - true) ** 2
            angle_n += 1
    # The predicted tip against where the truth's tip is one horizon later (inside the truth's span).
    predicted_sq, predicted_n, horizons = 0.0, 0, set()
    for r in tracked:
        horizon = r.get("prediction_horizon_ns", 0)
        if "predicted_tip" not in r or horizon <= 0 or r["stamp_ns"] + horizon > stamps[-1]:
            continue
        horizons.add(horizon)
        predicted_sq += math.dist(interpolate(stamps, tips, r["stamp_ns"] + horizon), r["predicted_tip"]) ** 2
        predicted_n += 1
    predicted_rmse_mm = 1e3 * math.sqrt(predicted_sq / predicted_n) if predicted_n else None
    tip_rmse_mm = 1e3 * math.sqrt(tip_sq / max(len(tracked), 1))
    angle_rmse_deg = math.degrees(math.sqrt(angle_sq / max(angle_n, 1)))
    tracked_fraction = len(tracked) / max(len(scored), 1)

    expected = truth_transitions(stamps, angles, args.grab_rad, args.release_rad)
    unmatched = list(expected)
    spurious, worst_delay = 0, 0.0
    for e in events:
        match = next((t for t in unmatched if t[0] == e["type"] and abs(t[1] - e["stamp_ns"]) <= args.event_window * 1e9),
                     None)
        if match is None:
            spurious += 1
        else:
            unmatched.remove(match)
            worst_delay = max(worst_delay, abs(match[1] - e["stamp_ns"]) * 1e-9)
    detected = len(expected) - len(unmatched)
    summary = {"records": len(scored), "tracked": tracked_fraction, "tip_rmse_mm": tip_rmse_mm,
               "tip_max_mm": 1e3 * tip_max, "predicted_tip_rmse_mm": predicted_rmse_mm,
               "prediction_horizons_ms": sorted(h / 1e6 for h in horizons), "angle_rmse_deg": angle_rmse_deg, "transitions": len(expected),
               "detected": detected, "spurious": spurious,
               "max_event_offset_ms": 1e3 * worst_delay}
    print(json.dumps(summary))

    failures = []
    if args.require_tip_rmse_mm is not None and not tip_rmse_mm <= args.require_tip_rmse_mm:
        failures.append(f"tip RMSE {tip_rmse_mm:.3f} mm > {args.require_tip_rmse_mm} mm")
    if args.require_angle_rmse_deg is not None and not angle_rmse_deg <= args.require_angle_rmse_deg:
        failures.append(f"joint-angle RMSE {angle_rmse_deg:.3f} deg > {args.require_angle_rmse_deg} deg")
    if args.require_predicted_rmse_mm is not None and not (
            predicted_rmse_mm is not None and predicted_rmse_mm <= args.require_predicted_rmse_mm):
        failures.append(f"predicted tip RMSE {predicted_rmse_mm} mm > {args.require_predicted_rmse_mm} mm "
                        "(None: no record with a predicted tip)")
    if args.require_tracked is not None and tracked_fraction < args.require_tracked:
        failures.append(f"tracked {tracked_fraction:.3f} < {args.require_tracked}")
    if args.require_events and (detected != len(expected) or spurious or not expected):
        failures.append(f"events: {detected} of {len(expected)} transitions detected, {spurious} spurious")
    for failure in failures:
        print("FAIL: " + failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
