#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Compares camera_node's FeatureFrames with panoptes_fake_gige's truth, frame by frame.

Frame ids on GigE Vision 1.x are 16-bit and skip 0, so truth ids cycle 1..65535 while the
FeatureFrame "frame" (the source's sequence) keeps counting: the truth of sequence s is id
(s - 1) % 65535 + 1. Prints one summary line of JSON; exits 1 if a requirement fails.
"""
import argparse
import json
import math
import sys


def load_jsonl(path):
    with open(path, encoding="utf-8") as handle:
        return [json.loads(line) for line in handle if line.strip()]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--truth", required=True)
    parser.add_argument("--features", required=True)
    parser.add_argument("--max-error-px", type=float, default=0.1)
    parser.add_argument("--min-detected", type=float, default=0.99)
    parser.add_argument("--min-frames", type=int, default=1)
    parser.add_argument("--match-radius-px", type=float, default=2.0)
    parser.add_argument("--max-stamp-error-ms", type=float, default=0,
                        help="if > 0: bound on |stamp - (device time + latency floor + exposure/2)| after the "
                        "first --stamp-warmup frames; the fake's device clock is the wall clock and its latency "
                        "floor is the smallest ready_ns - device_ns (it stamps frames before rendering them)")
    parser.add_argument("--stamp-warmup", type=int, default=20)
    parser.add_argument("--exposure-us", type=float, default=10000)
    args = parser.parse_args()

    truth = {}
    for record in load_jsonl(args.truth):
        truth[record["frame"]] = record  # a restarted id (rare) keeps the newest
    frames = load_jsonl(args.features)
    # The latency floor a mapper can have seen by frame i: the smallest ready - device up to i.
    floor_ns = {}
    running = None
    for record in sorted(truth.values(), key=lambda r: r["device_ns"]):  # ids wrap, stamps do not
        latency = record.get("ready_ns", record["device_ns"]) - record["device_ns"]
        running = latency if running is None else min(running, latency)
        floor_ns[record["frame"]] = running

    problems = []
    matched = expected = 0
    errors = []
    stamp_errors_ms = []
    previous = None
    for index, frame in enumerate(frames):
        sequence = frame["frame"]
        if previous is not None and sequence <= previous:
            problems.append(f"frame {sequence} does not follow {previous}")
        previous = sequence
        record = truth.get((sequence - 1) % 65535 + 1)
        if record is None:
            problems.append(f"frame {sequence} has no truth")
            continue
        blobs = frame["blobs"]
        for x, y in record["spots"]:
            expected += 1
            best = min((math.hypot(b["x"] - x, b["y"] - y) for b in blobs), default=math.inf)
            if best <= args.match_radius_px:
                matched += 1
                errors.append(best)
        if args.max_stamp_error_ms > 0 and index >= args.stamp_warmup:
            ideal = record["device_ns"] + floor_ns[record["frame"]] + args.exposure_us * 500
            stamp_errors_ms.append((frame["stamp_ns"] - ideal) / 1e6)

    detected = matched / expected if expected else 0.0
    worst = max(errors, default=math.inf)
    rms = math.sqrt(sum(e * e for e in errors) / len(errors)) if errors else math.inf
    summary = {"frames": len(frames), "spots": expected, "detected": round(detected, 5),
               "rms_px": round(rms, 4), "max_px": round(worst, 4)}
    if stamp_errors_ms:
        summary["stamp_error_ms"] = [round(min(stamp_errors_ms), 3), round(max(stamp_errors_ms), 3)]
    print(json.dumps(summary))

    if len(frames) < args.min_frames:
        problems.append(f"{len(frames)} frames, expected at least {args.min_frames}")
    if detected < args.min_detected:
        problems.append(f"detected {detected:.4f} of the spots, expected at least {args.min_detected}")
    if worst > args.max_error_px:
        problems.append(f"worst centroid error {worst:.4f} px > {args.max_error_px} px")
    if stamp_errors_ms and max(abs(e) for e in stamp_errors_ms) > args.max_stamp_error_ms:
        problems.append(f"stamp errors span [{min(stamp_errors_ms):.3f}, {max(stamp_errors_ms):.3f}] ms, "
                        f"bound {args.max_stamp_error_ms} ms")
    for problem in problems[:10]:
        print("problem:", problem, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
