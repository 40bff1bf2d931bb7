#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Names after every camera stalled (docs/estimator.md, "After every camera stalled").

test_live_labels' scene offline: the Gait2392 subject01 model from its static trial, walk1 through
walk8's eight asynchronous cameras (0.3 false blobs per frame, two markers hidden for 0.6-0.8 s),
10 s. For each stall length and instant, every camera's frames from that instant on are removed
for that long (a machine too loaded to run the camera_nodes drops them in their queues), the
offline estimator labels the rest (`estimator_node --no-dds --subjects`, default configuration)
and the names are scored as the live test scores them (tests/integration/score_labels.py). The
report gives, per stall length, the worst instant's names right and wrong and the left/right
swaps (marker-frames) summed over the instants.

  stall_labels.py --bin build/bin --work /tmp/stall
  stall_labels.py --bin build/bin --work /tmp/stall --stalls-ms 46 --at-s 7.614 --keep

Exit status 1 when --require-right or --require-no-swaps is not met; 2 when a tool fails.
"""
import argparse
import concurrent.futures
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
STATIC = os.path.join(SOURCE, "..", "shared", "data", "static")
HIDDEN = [("L.Shank.Front", 3.0, 3.8), ("L.Wrist.Lat", 6.0, 6.6)]
EPOCH_NS = 1_700_000_000_000_000_000


def run(command, what):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{what} failed (exit {result.returncode}): {result.stderr.strip()[-400:]}")
    return result.stdout + result.stderr


def prepare(args):
    """The subject model, the settings and the simulated cameras' features, once per work folder."""
    work = args.work
    os.makedirs(os.path.join(work, "models"), exist_ok=True)
    static = os.path.join(STATIC, "gait2392_subject01_static.trc")
    walk1 = os.path.join(STATIC, "gait2392_subject01_walk1.trc")
    for path in (static, walk1):
        if not os.path.exists(path):
            raise RuntimeError(f"{path}: missing (../shared/data beside the checkout, data/README.md)")
    run([os.path.join(args.bin, "panoptes_label"), "model", "--static", static, "--markerset",
         os.path.join(SOURCE, "deploy", "markersets", "gait2392.yaml"), "--out",
         os.path.join(work, "models", "s1.yaml"), "--subject", "s1"], "panoptes_label model")
    with open(os.path.join(work, "settings.yaml"), "w") as f:
        f.write("subjects:\n  models: [models/s1.yaml]\n  soft_segments: [Torso]\n")
    scene = []
    for line in open(os.path.join(SOURCE, "deploy", "scenes", "walk8.yaml")):
        if line.startswith("duration:"):
            line = "duration: 10.0\n"
        elif line.startswith("  false_blobs:"):
            line = "  false_blobs: 0.3\n"
        elif line.startswith("  file:"):
            line = f"  file: {walk1}\n"
        elif line.startswith("  offset:"):
            line = "  offset: [-0.58, 0, 0]\n"
        scene.append(line)
    scene.append("  hide:\n")
    scene += [f"    - {{marker: {m}, from: {a}, to: {b}}}\n" for m, a, b in HIDDEN]
    with open(os.path.join(work, "walk1.yaml"), "w") as f:
        f.writelines(scene)
    run([os.path.join(args.bin, "panoptes_sim"), "features", "--scene", os.path.join(work, "walk1.yaml"),
         "--out-dir", os.path.join(work, "sim")], "panoptes_sim features")


def cell(args, at_s, stall_ms):
    """Names scored with every camera's frames in [at_s, at_s + stall_ms) removed."""
    name = f"at{at_s}_stall{stall_ms:g}"
    folder = os.path.join(args.work, name)
    os.makedirs(folder, exist_ok=True)
    sim = os.path.join(args.work, "sim")
    cut_from, cut_to = EPOCH_NS + int(at_s * 1e9), EPOCH_NS + int((at_s + stall_ms * 1e-3) * 1e9)
    inputs = []
    for file in sorted(f for f in os.listdir(sim) if f.startswith("cam") and f.endswith(".jsonl")):
        out = os.path.join(folder, file)
        with open(os.path.join(sim, file)) as src, open(out, "w") as dst:
            for line in src:
                stamp = json.loads(line)["stamp_ns"]
                if not cut_from <= stamp < cut_to:
                    dst.write(line)
        inputs.append(out)
    labels = os.path.join(folder, "labels.jsonl")
    log = run([os.path.join(args.bin, "estimator_node"), "--no-dds", "--calibration",
               os.path.join(sim, "calibration.yaml"), "--config", os.path.join(args.work, "settings.yaml"),
               "--frames", "per-camera", "--in-features", *inputs, "--out-labels", labels], f"{name}: estimator_node")
    hidden = [a for m, _, end in HIDDEN for a in ("--hidden", f"{m}:{end}")]
    score = subprocess.run([sys.executable, os.path.join(SOURCE, "tests", "integration", "score_labels.py"), labels,
                            os.path.join(sim, "truth.jsonl"), "--skip-s", "0.5", "--truth-shift-ns", "0", *hidden,
                            "--explain", "3"], capture_output=True, text=True)
    if not score.stdout.strip():
        raise RuntimeError(f"{name}: score_labels.py: {score.stderr.strip()[-400:]}")
    result = json.loads(score.stdout)
    paused = re.search(r"input paused (\d+) times", log)
    if not args.keep:
        for file in os.listdir(folder):
            os.remove(os.path.join(folder, file))
        os.rmdir(folder)
    return {"at_s": at_s, "stall_ms": stall_ms, "right_percent": result["right_percent"],
            "wrong_percent": result["wrong_percent"], "left_right_swaps": result["left_right_swaps"],
            "explain": [line for line in score.stderr.splitlines() if line.startswith("wrong:")],
            "input_pauses": int(paused.group(1)) if paused else 0}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bin", required=True, help="folder of estimator_node, panoptes_sim, panoptes_label")
    parser.add_argument("--work", required=True, help="scratch folder (scene, features, one folder per cell)")
    parser.add_argument("--stalls-ms", default="0,30,46,80,150", help="stall lengths (default: %(default)s)")
    parser.add_argument("--at-s", default="2.0,4.5,7.614,9.0", help="scene times they start at (default: %(default)s)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="cells run at once (default: cores)")
    parser.add_argument("--keep", action="store_true", help="keep each cell's inputs and labels")
    parser.add_argument("--json", help="write the cells here")
    parser.add_argument("--require-right", type=float, help="every cell's names right at least this (%%)")
    parser.add_argument("--require-no-swaps", action="store_true", help="no left/right swap in any cell")
    args = parser.parse_args()
    stalls = [float(s) for s in args.stalls_ms.split(",")]
    instants = [float(s) for s in args.at_s.split(",")]
    start = time.time()
    try:
        prepare(args)
        jobs = [(a, s) for s in stalls for a in (instants if s > 0 else instants[:1])]
        cells = []
        with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
            futures = {pool.submit(cell, args, a, s): (a, s) for a, s in jobs}
            for done in concurrent.futures.as_completed(futures):
                c = done.result()
                cells.append(c)
                print(f"[{len(cells)}/{len(jobs)}] stall {c['stall_ms']:g} ms at {c['at_s']} s: "
                      f"{c['right_percent']:.3f} % right, {c['wrong_percent']:.3f} % wrong, "
                      f"{c['left_right_swaps']} swap marker-frames, {c['input_pauses']} input pause(s)"
                      + (f"; {c['explain'][0]}" if c["explain"] else ""),
                      flush=True)
    except RuntimeError as error:
        print(f"stall_labels: {error}", file=sys.stderr)
        return 2
    print("\n| stall | names right, worst | wrong, worst | L/R swap marker-frames, sum |")
    print("| --- | --- | --- | --- |")
    for s in stalls:
        row = [c for c in cells if c["stall_ms"] == s]
        print(f"| {s:g} ms | {min(c['right_percent'] for c in row):.3f} % | "
              f"{max(c['wrong_percent'] for c in row):.3f} % | {sum(c['left_right_swaps'] for c in row)} |")
    print(f"{len(cells)} cells in {time.time() - start:.1f} s")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(sorted(cells, key=lambda c: (c["stall_ms"], c["at_s"])), f, indent=1)
    failed = False
    if args.require_right is not None:
        for c in cells:
            if c["right_percent"] < args.require_right:
                print(f"FAIL: stall {c['stall_ms']:g} ms at {c['at_s']} s: {c['right_percent']:.3f} % right "
                      f"< {args.require_right} %", file=sys.stderr)
                failed = True
    if args.require_no_swaps:
        for c in cells:
            if c["left_right_swaps"]:
                print(f"FAIL: stall {c['stall_ms']:g} ms at {c['at_s']} s: {c['left_right_swaps']} swap marker-frames",
                      file=sys.stderr)
                failed = True
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
