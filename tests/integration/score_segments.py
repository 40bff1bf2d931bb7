#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Scores the segment poses a client received (panoptes_client_probe --out) against the simulator's
truth.jsonl (docs/marker_sets.md, "Segment poses live").

Each segment's description (kind "segment") holds its tracked markers in the pose's frame. For every
frame in which a segment is posed, its markers are placed by the pose and each is matched to the
nearest true marker (the truth interpolated to the frame's stamp): the distance is how far the pose
puts the segment's markers from where they really were (soft tissue and fit included). Per segment:
the share of frames posed and the RMS distance. Prints one JSON object; exit 1 when --max-rms-mm or
--min-posed are not met by a segment not in --exclude. With --gaps-from, frames within --after-gap-ms
of the end of a gap in the estimator's input are left out (score_labels.py, docs/testing.md "Live
tests under load"). With --skip-between FROM_S:TO_S (scene time from the truth's first record;
repeatable), frames in that interval are left out: a marker the scene hid (trc.hide) is missing from
the truth there, so the pose's placement of it would be matched to another marker."""
import argparse
import json
import math
import sys

from score_labels import after_gap, input_gap_ends, load_truth, truth_at


def rotate(q, v):
    x, y, z, w = q
    # v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    ux = (y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0])
    uux = (y * ux[2] - z * ux[1], z * ux[0] - x * ux[2], x * ux[1] - y * ux[0])
    return [v[i] + 2.0 * (w * ux[i] + uux[i]) for i in range(3)]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("client")
    parser.add_argument("truth")
    parser.add_argument("--truth-shift-ns", type=int, default=0)
    parser.add_argument("--skip-s", type=float, default=0.0)
    parser.add_argument("--every", type=int, default=1, help="score every n-th frame only")
    parser.add_argument("--exclude", default="", help="comma-separated segment names (after the subject)")
    parser.add_argument("--max-rms-mm", type=float, default=None)
    parser.add_argument("--min-posed", type=float, default=None, help="percent of frames")
    parser.add_argument("--skip-between", action="append", default=[], metavar="FROM_S:TO_S",
                        help="leave out frames in this interval of scene time (a hidden marker)")
    parser.add_argument("--gaps-from", default=None, help="an --out-labels file whose gaps are input gaps")
    parser.add_argument("--gap-ms", type=float, default=50.0)
    parser.add_argument("--after-gap-ms", type=float, default=500.0)
    args = parser.parse_args()
    gap_ends = input_gap_ends(args.gaps_from, args.gap_ms) if args.gaps_from else []
    stamps, markers = load_truth(args.truth, True)  # every subject's markers
    stamps = [s + args.truth_shift_ns for s in stamps]
    skipped = []
    for interval in args.skip_between:
        try:
            begin, end = (stamps[0] + int(float(x) * 1e9) for x in interval.split(":"))
        except ValueError:
            parser.error(f"--skip-between {interval}: expected FROM_S:TO_S in seconds")
        skipped.append((begin, end))
    layouts, frames = {}, []
    for line in open(args.client):
        record = json.loads(line)
        if record.get("type") == "descriptions":
            layouts.update({b["name"]: b["markers"] for b in record["bodies"] if b["kind"] == "segment"})
        elif record.get("type") == "frame":
            frames.append(record)
    first = frames[0]["stamp_ns"] if frames else 0
    excluded = {name for name in args.exclude.split(",") if name}
    stats = {name: {"frames": 0, "posed": 0, "sum2": 0.0, "n": 0} for name in layouts}
    for frame in frames[::max(args.every, 1)]:
        if (frame["stamp_ns"] - first) * 1e-9 < args.skip_s or not stamps[0] <= frame["stamp_ns"] <= stamps[-1]:
            continue
        if after_gap(gap_ends, frame["stamp_ns"], args.after_gap_ms):
            continue
        if any(begin <= frame["stamp_ns"] < end for begin, end in skipped):
            continue
        truth = list(truth_at(stamps, markers, frame["stamp_ns"]).values())
        for body in frame["bodies"]:
            if body["name"] not in layouts:
                continue
            s = stats[body["name"]]
            s["frames"] += 1
            if not body["valid"]:
                continue
            s["posed"] += 1
            for m in layouts[body["name"]]:
                r = rotate(body["q"], m)
                p = [r[i] + body["p"][i] for i in range(3)]
                d = min(math.dist(p, t) for t in truth)
                s["sum2"] += d * d
                s["n"] += 1
    segments = {}
    for name, s in sorted(stats.items()):
        segments[name] = {"posed_percent": round(100.0 * s["posed"] / max(s["frames"], 1), 2),
                          "rms_mm": round(1e3 * math.sqrt(s["sum2"] / max(s["n"], 1)), 2)}
    judged = {n: v for n, v in segments.items() if n.split("/")[-1] not in excluded}
    result = {
        "segments_described": len(layouts),
        "frames": len(frames),
        "worst_rms_mm": max((v["rms_mm"] for v in judged.values()), default=None),
        "least_posed_percent": min((v["posed_percent"] for v in judged.values()), default=None),
        "segments": segments,
    }
    print(json.dumps(result))
    ok = bool(judged) and (args.max_rms_mm is None or result["worst_rms_mm"] <= args.max_rms_mm) and (
        args.min_posed is None or result["least_posed_percent"] >= args.min_posed)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
