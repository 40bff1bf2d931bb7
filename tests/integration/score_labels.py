#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Scores estimator_node --out-labels against the simulator's truth.jsonl (docs/marker_sets.md).

A confirmed track within --match-m of a true marker (truth interpolated to the record's stamp) is a
visible marker-frame of that marker; it is right when it carries that marker's name, wrong when it
carries another. A left/right swap is a wrong name that differs from the true one only by its side
prefix. With --by-subject the truth's names are "<subject>/<marker>" (the scene's trc prefixes) and
a name is right only with its subject; a name of the other subject is a subject crossing. Return latency: for each track that starts on a marker whose name was seen before, the
time from the track's first record to its first right name. With --gaps-from, the marker-frames
within --after-gap-ms of the end of a gap in the estimator's input (no record for longer than
--gap-ms in that --out-labels file: a machine too loaded to run every camera, issue 37) are scored
apart ("after_gap_*") and bounded by --max-wrong-after-gap; --max-after-gap-s bounds the time they
cover. With --hidden NAME:END_S (a marker the scene hid from every camera until END_S of scene time,
the truth's first record being scene time 0; repeatable), the time from the first track on NAME
after END_S to its first right name ("reappearances"; never named counts as failing
--max-reappear-ms). Prints one JSON object; exit 1 when a bound is not met."""
import argparse
import bisect
import json
import math
import sys


def load_truth(path, by_subject):
    stamps, markers = [], []
    for line in open(path):
        record = json.loads(line)
        stamps.append(record["stamp_ns"])
        markers.append({(m["name"] if by_subject else m["name"].split("/")[-1]): m["p"] for m in record["markers"]})
    return stamps, markers


def truth_at(stamps, markers, stamp):
    i = bisect.bisect_right(stamps, stamp)
    if i == 0 or i == len(stamps):
        return markers[min(i, len(stamps) - 1)]
    a, b = markers[i - 1], markers[i]
    w = (stamp - stamps[i - 1]) / (stamps[i] - stamps[i - 1])
    return {n: [pa + w * (pb - pa) for pa, pb in zip(a[n], b[n])] for n in a if n in b}


def input_gap_ends(path, gap_ms):
    """The stamps that end a gap of more than gap_ms between consecutive records of path."""
    stamps = sorted(json.loads(line)["stamp_ns"] for line in open(path) if line.strip())
    return [b for a, b in zip(stamps, stamps[1:]) if b - a > gap_ms * 1e6]


def after_gap(gap_ends, stamp, after_gap_ms):
    i = bisect.bisect_right(gap_ends, stamp)
    return i > 0 and stamp - gap_ends[i - 1] < after_gap_ms * 1e6


def covered_s(gap_ends, after_gap_ms):
    """Seconds within after_gap_ms of a gap's end (overlaps counted once)."""
    total, reach = 0, None
    for end in gap_ends:
        start = end if reach is None else max(end, reach)
        reach = end + after_gap_ms * 1e6
        total += max(0, reach - start)
    return total * 1e-9


def side_swapped(name, truth_name):
    for a, b in (("R.", "L."), ("L.", "R.")):
        if name.startswith(a) and truth_name.startswith(b) and name[2:] == truth_name[2:]:
            return True
    return False


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("labels")
    parser.add_argument("truth")
    parser.add_argument("--match-m", type=float, default=0.02)
    parser.add_argument("--truth-shift-ns", type=int, default=0,
                        help="added to the truth's stamps (a replay's --sim-epoch-ns minus the scene's epoch)")
    parser.add_argument("--skip-s", type=float, default=0.0, help="ignore records before this (from the first)")
    parser.add_argument("--by-subject", action="store_true",
                        help="truth names are <subject>/<marker>; a name is right only with its subject")
    parser.add_argument("--min-right", type=float, default=None)
    parser.add_argument("--max-wrong", type=float, default=None)
    parser.add_argument("--max-return-ms", type=float, default=None)
    parser.add_argument("--explain", type=int, default=0, metavar="N",
                        help="also print to stderr the N most frequent wrong names (true, given, "
                        "marker-frames, first and last second from the first record)")
    parser.add_argument("--hidden", action="append", default=[], metavar="NAME:END_S",
                        help="a marker hidden until END_S (scene s): time to its name after it reappears")
    parser.add_argument("--max-reappear-ms", type=float, default=None)
    parser.add_argument("--gaps-from", default=None, help="an --out-labels file whose gaps are input gaps")
    parser.add_argument("--gap-ms", type=float, default=50.0)
    parser.add_argument("--after-gap-ms", type=float, default=500.0)
    parser.add_argument("--max-wrong-after-gap", type=float, default=None)
    parser.add_argument("--max-after-gap-s", type=float, default=None)
    args = parser.parse_args()
    gap_ends = input_gap_ends(args.gaps_from, args.gap_ms) if args.gaps_from else []
    stamps, markers = load_truth(args.truth, args.by_subject)
    stamps = [stamp + args.truth_shift_ns for stamp in stamps]
    hidden = {}  # name -> [end stamp, first track stamp, named stamp]
    for entry in args.hidden:
        name, _, end_s = entry.rpartition(":")
        try:
            hidden[name] = [stamps[0] + int(float(end_s) * 1e9), None, None]
        except ValueError:
            parser.error(f"--hidden {entry}: expected NAME:END_S, END_S in seconds")
    visible = right = wrong = swaps = ghost_named = crossings = 0
    after_gap_visible = after_gap_wrong = 0
    first_stamp = None
    track_start, track_marker, track_named, seen_names = {}, {}, set(), set()
    returns = []
    wrong_by_pair = {}  # (true, given) -> [count, first s, last s]
    for line in open(args.labels):
        record = json.loads(line)
        stamp = record["stamp_ns"]
        first_stamp = stamp if first_stamp is None else first_stamp
        truth = truth_at(stamps, markers, stamp)
        for entry in record["tracks"]:
            best, best_d = None, args.match_m
            for name, p in truth.items():
                d = math.dist(p, entry["p"])
                if d < best_d:
                    best, best_d = name, d
            label = entry.get("marker")
            if args.by_subject and label is not None:
                label = entry.get("subject", "") + "/" + label
            track = entry["track"]
            if track not in track_start:
                track_start[track] = stamp
                track_marker[track] = best
            if best is None:
                ghost_named += label is not None
                continue
            if (stamp - first_stamp) * 1e-9 < args.skip_s:
                continue
            if after_gap(gap_ends, stamp, args.after_gap_ms):
                after_gap_visible += 1
                after_gap_wrong += label is not None and label != best
                continue
            visible += 1
            reappear = hidden.get(best)
            if reappear and stamp >= reappear[0]:
                reappear[1] = stamp if reappear[1] is None else reappear[1]
                if label == best and reappear[2] is None:
                    reappear[2] = stamp
            if label == best:
                right += 1
                if track not in track_named:
                    track_named.add(track)
                    if best in seen_names and track_marker[track] == best:
                        returns.append((stamp - track_start[track]) * 1e-6)
                seen_names.add(best)
            elif label is not None:
                wrong += 1
                at_s = (stamp - first_stamp) * 1e-9
                pair = wrong_by_pair.setdefault((best, label), [0, at_s, at_s])
                pair[0] += 1
                pair[2] = at_s
                name, true_name = label.split("/")[-1], best.split("/")[-1]
                swaps += side_swapped(name, true_name)
                crossings += args.by_subject and label.split("/")[0] != best.split("/")[0]
    result = {
        "visible_marker_frames": visible,
        "right_percent": 100.0 * right / max(visible, 1),
        "wrong_percent": 100.0 * wrong / max(visible, 1),
        "left_right_swaps": swaps,
        "subject_crossings": crossings,
        "ghost_tracks_named": ghost_named,
        "returns": len(returns),
        "worst_return_ms": max(returns, default=0.0),
    }
    if hidden:
        result["reappearances"] = {name: None if v[1] is None or v[2] is None else (v[2] - v[1]) * 1e-6
                                   for name, v in hidden.items()}
        times = result["reappearances"].values()
        result["worst_reappear_ms"] = None if None in times else max(times)  # None: one never named
    if args.gaps_from:
        result["input_gaps"] = len(gap_ends)
        result["after_gap_s"] = covered_s(gap_ends, args.after_gap_ms)
        result["after_gap_marker_frames"] = after_gap_visible
        result["after_gap_wrong_percent"] = 100.0 * after_gap_wrong / max(after_gap_visible, 1)
    print(json.dumps(result))
    ranked = sorted(wrong_by_pair.items(), key=lambda item: -item[1][0])
    for (true_name, given), (count, first_s, last_s) in ranked[:args.explain]:
        print(f"wrong: {true_name} named {given}: {count} marker-frames, {first_s:.3f}-{last_s:.3f} s",
              file=sys.stderr)
    ok = (args.min_right is None or result["right_percent"] >= args.min_right) and (
        args.max_wrong is None or result["wrong_percent"] <= args.max_wrong) and (
        args.max_return_ms is None or result["worst_return_ms"] <= args.max_return_ms) and (
        args.max_reappear_ms is None or result.get("worst_reappear_ms", 0) is not None and
        result.get("worst_reappear_ms", 0) <= args.max_reappear_ms) and (
        args.max_wrong_after_gap is None or result.get("after_gap_wrong_percent", 0) <= args.max_wrong_after_gap) and (
        args.max_after_gap_s is None or result.get("after_gap_s", 0) <= args.max_after_gap_s)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
