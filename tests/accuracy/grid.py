#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Accuracy grid (issue 35 item 1): rigs x motions x clutter x seeds, default configuration.

Every cell writes a simulator scene, runs `panoptes_sim features`, the offline estimator
(`estimator_node --no-dds`, no configuration file: the defaults) and `panoptes_eval`, and reports
RMSE, ID switches, coverage and false records. The report ends with the worst cell and the median.

  grid.py --bin build/bin --work /tmp/grid            # the CI subset (short scenes)
  grid.py --bin build/bin --work /tmp/grid --long     # the full grid: 9 rigs x 5 motions x 3 x 3
  grid.py ... --cells 'ring8/club/*'                  # cells matching a glob (rig/motion/clutter/seed)

Rigs: 4, 6 and 8 cameras as a ring (radius 4 m), a corridor (two walls 5 m apart) and a ceiling
(3.2 m high, looking down); 1280x1024, f = 1000 px, 100-120 Hz, all phases different, 0.1 px
centroid noise, merging spots. Motions: the 41-marker walk (real motion capture, 1.5 m/s), the
same played twice as fast (run, 3 m/s), dance (12 markers on fast Lissajous paths, up to ~6 m/s),
club (3 markers on a swung club, head at 25 m/s, 400 m/s^2) and ball (thrown to and fro at 25 m/s,
caught and thrown back over 0.1 s, 785 m/s^2). Clutter: 0, 0.3 and 1 false blob per camera frame.

Requirements (--require-*) make the exit status 1; a cell that cannot run (no marker trackable,
a tool failing) fails loudly, naming the cell, with exit status 2.
"""
import argparse
import fnmatch
import json
import math
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(os.path.dirname(HERE))
TRC = os.path.join(SOURCE, "tests", "data", "walk_41markers_100hz.trc")
RATES = [100, 110, 120, 105, 115, 100, 110, 120]


class CellError(Exception):
    pass


def look_at_camera(index, eye, target):
    return {
        "id": f"cam{index}",
        "K": [1000.0 + 1.3 * index, 1000.2 + 1.1 * index, 640.0 + 0.7 * index, 512.0 - 0.5 * index],
        "look_at": {"eye": eye, "target": target},
        "rate": RATES[index],
        "phase": round(0.0013 * ((index * 5) % 8), 4),
    }


def rig_cameras(layout, count, blind=False):
    cams = []
    for i in range(count):
        if layout == "ring":
            a = 2 * math.pi * i / count + 0.3
            eye = [4.0 * math.cos(a), 4.0 * math.sin(a), 2.4 + 0.1 * (i % 3)]
            target = [0.0, 0.0, 1.0]
        elif layout == "corridor":
            # Two walls at y = +-2.5, cameras spread along x, each looking across and inwards.
            side = 1 if i % 2 == 0 else -1
            k = i // 2
            n = (count + 1) // 2
            x = -3.0 + 6.0 * (k + 0.5) / n
            eye = [x, 2.5 * side, 2.5]
            target = [0.4 * x, 0.0, 1.0]
        elif layout == "ceiling":
            a = 2 * math.pi * i / count
            eye = [2.2 * math.cos(a), 2.2 * math.sin(a), 3.2]
            target = [-0.4 * math.cos(a), -0.4 * math.sin(a), 0.8]
        else:
            raise CellError(f"unknown rig layout {layout}")
        if blind:  # looking away from the volume: nothing to see (the loud-failure check)
            target = [2 * e - t for e, t in zip(eye, target)]
        cams.append(look_at_camera(i, [round(v, 4) for v in eye], target))
    return cams


def sampled_path(fn, period, step=0.001):
    times = [round(k * step, 6) for k in range(int(round(period / step)) + 1)]
    points = [[round(v, 6) for v in fn(t % period)] for t in times]
    return {"type": "waypoints", "points": points, "times": times, "loop": True}


def club_markers():
    # A pendulum swing about a pivot 1.7 m up: theta(t) = 2.5 sin(2 pi f t), head (r = 1.4 m) at
    # 25 m/s through the bottom; markers at the hands, mid-shaft and head.
    amp, radius_head, speed = 2.5, 1.4, 25.0
    f = speed / (radius_head * amp * 2 * math.pi)
    period = 1.0 / f
    markers = []
    for name, r in (("club/grip", 0.6), ("club/shaft", 1.0), ("club/head", radius_head)):
        def pos(t, r=r):
            th = amp * math.sin(2 * math.pi * f * t)
            return [0.3 + r * math.sin(th), 0.2, 1.7 - r * math.cos(th)]
        markers.append({"name": name, "path": sampled_path(pos, period)})
    return markers


def ball_markers():
    # Thrown to and fro along x between +-1.2 m at 25 m/s (gravity in flight), each catch and
    # throw a smooth reversal over 0.1 s reaching +-2.0 m (cosine velocity profile, peak 785 m/s^2).
    v, tau, span = 25.0, 0.1, 2.4
    flight = span / v
    half = flight + tau
    period = 2 * half
    arc = tau * v / math.pi  # how far a reversal overshoots the end of a flight

    def pos(t):
        direction = 1 if t < half else -1
        u = t if t < half else t - half
        x0 = -span / 2 - arc if direction > 0 else span / 2 + arc
        if u < flight:
            x = x0 + direction * (arc + v * u)
            z = 1.3 + 0.5 * 9.81 * u * (flight - u)
        else:
            w = u - flight  # reversal: v cos(pi w / tau)
            x = x0 + direction * (arc + v * flight + v * tau / math.pi * math.sin(math.pi * w / tau))
            z = 1.3
        return [x, 0.1, z]

    return [{"name": "ball", "path": sampled_path(pos, period)}]


def dance_markers():
    markers = []
    for i in range(12):
        cx = -0.75 + 0.5 * (i % 4)
        cz = 0.6 + 0.5 * (i // 4)
        fx, fy, fz = 2.0 + 0.37 * (i % 5), 2.6 + 0.29 * (i % 3), 3.1 - 0.23 * (i % 4)
        markers.append({
            "name": f"dance/{i}",
            "path": {"type": "lissajous", "center": [cx, 0.15 * (i % 3) - 0.15, cz],
                     "amplitude": [0.2, 0.2, 0.18], "frequency": [fx, fy, fz],
                     "phase": [0.7 * i, 1.3 * i, 0.4 * i]},
        })
    return markers


def run_trc(work):
    """The walk played twice as fast (3 m/s, 4x the accelerations): the TRC's Time column halved."""
    out = os.path.join(work, "run_41markers_200hz.trc")
    if os.path.exists(out):
        return out
    lines = open(TRC).read().splitlines()
    result = []
    for n, line in enumerate(lines):
        cols = line.split("\t")
        if n >= 5 and len(cols) > 2 and cols[0].strip().isdigit():
            cols[1] = repr(float(cols[1]) / 2)
        result.append("\t".join(cols))
    with open(out + ".tmp", "w") as f:
        f.write("\n".join(result) + "\n")
    os.replace(out + ".tmp", out)
    return out


def scene(rig, count, motion, clutter, seed, duration, work, blind=False):
    s = {
        "seed": seed,
        "duration": duration,
        "defaults": {
            "width": 1280, "height": 1024, "distortion": [-0.08, 0.05, 0.0002, 0.0004, -0.01],
            "exposure": 0.0008, "pixel_noise": 1.0, "centroid_noise": 0.1, "false_blobs": clutter,
            "merge_distance": 3.0, "latency": 0.002,
        },
        "cameras": rig_cameras(rig, count, blind),
    }
    if motion in ("walk", "run"):
        s["trc"] = {"file": TRC if motion == "walk" else run_trc(work), "up_axis": "y",
                    "offset": [-0.81, -0.25, 0.0], "loop": "pingpong",
                    "turnaround": 0.5 if motion == "walk" else 0.25,
                    "start": 0.125 if motion == "walk" else 0.0625, "radius": 0.007,
                    "occlusion": {"facing_angle": 100}}
    elif motion == "dance":
        s["markers"] = dance_markers()
    elif motion == "club":
        s["markers"] = club_markers()
    elif motion == "ball":
        s["markers"] = ball_markers()
    else:
        raise CellError(f"unknown motion {motion}")
    return s


RIGS = [(layout, n) for layout in ("ring", "corridor", "ceiling") for n in (4, 6, 8)]
MOTIONS = ["walk", "run", "dance", "club", "ball"]
CLUTTER = [0.0, 0.3, 1.0]
SEEDS = [1, 2, 3]

# The CI subset: every rig, motion, clutter level and seed appears at least once (a covering
# design, 15 cells), on short scenes.
CI_CELLS = [
    ("ring", 8, "walk", 0.0, 1), ("corridor", 6, "walk", 1.0, 2), ("ceiling", 4, "walk", 0.3, 3),
    ("ring", 6, "run", 0.3, 1), ("ceiling", 8, "run", 1.0, 2), ("corridor", 4, "run", 0.0, 3),
    ("corridor", 8, "dance", 0.3, 1), ("ring", 4, "dance", 1.0, 2), ("ceiling", 6, "dance", 0.0, 3),
    ("ring", 8, "club", 1.0, 1), ("ceiling", 6, "club", 0.3, 2), ("corridor", 6, "club", 0.0, 3),
    ("ring", 6, "ball", 0.0, 1), ("corridor", 8, "ball", 0.3, 2), ("ceiling", 8, "ball", 1.0, 3),
]


def cell_name(rig, n, motion, clutter, seed):
    return f"{rig}{n}/{motion}/c{clutter:g}/s{seed}"


def run(cmd, name, log):
    with open(log, "w") as out:
        r = subprocess.run(cmd, stdout=out, stderr=subprocess.STDOUT)
    return r.returncode


def run_cell(args, rig, n, motion, clutter, seed):
    name = cell_name(rig, n, motion, clutter, seed)
    work = os.path.join(args.work, name.replace("/", "_"))
    os.makedirs(work, exist_ok=True)
    duration = args.duration if args.duration else (12.0 if args.long else 2.5)
    path = os.path.join(work, "scene.yaml")
    with open(path, "w") as f:
        json.dump(scene(rig, n, motion, clutter, seed, duration, args.work, args.blind), f)
    b = args.bin
    if run([f"{b}/panoptes_sim", "features", "--scene", path, "--out-dir", work], name,
           os.path.join(work, "sim.log")) != 0:
        raise CellError(f"cell {name}: panoptes_sim failed (see {work}/sim.log)")
    feats = sorted(os.path.join(work, x) for x in os.listdir(work) if x.startswith("cam") and x.endswith(".jsonl"))
    est = [f"{b}/estimator_node", "--no-dds", "--quiet", "--calibration", os.path.join(work, "calibration.yaml"),
           "--in-features", *feats, "--out-tracks", os.path.join(work, "tracks.jsonl")]
    if args.config:
        est += ["--config", args.config]
    if run(est, name, os.path.join(work, "estimator.log")) != 0:
        raise CellError(f"cell {name}: estimator_node failed (see {work}/estimator.log)")
    summary = os.path.join(work, "eval.json")
    rc = run([f"{b}/panoptes_eval", "--scene", path, "--tracks", os.path.join(work, "tracks.jsonl"),
              "--warmup", str(args.warmup), "--summary-json", summary] + ([] if args.records_only else ["--every-frame"]),
             name, os.path.join(work, "eval.log"))
    if not os.path.exists(summary):
        raise CellError(f"cell {name}: panoptes_eval exit {rc}, no summary (see {work}/eval.log)")
    e = json.load(open(summary))
    trackable = sum(m.get("trackable", 0) or 0 for m in e.get("markers", []))
    if trackable == 0 or e.get("coverage") is None:
        raise CellError(f"cell {name}: no marker was ever trackable (seen by >= 2 cameras): the rig sees nothing")
    return {"cell": name, "rig": f"{rig}{n}", "motion": motion, "clutter": clutter, "seed": seed,
            "rmse_mm": e.get("rmse_mm"), "id_switches": e.get("id_switches", 0), "id_swaps": e.get("id_swaps", 0),
            "coverage": e["coverage"],
            "false_records": e.get("false_records", 0), "false_fraction": e.get("false_record_fraction", 0.0)}


def fmt(r):
    rmse = "-" if r["rmse_mm"] is None else f"{r['rmse_mm']:.3f}"
    return (f"| {r['cell']} | {rmse} | {r['id_switches']} | {r.get('id_swaps', 0)} | {100 * r['coverage']:.2f} | "
            f"{r['false_records']} ({100 * r['false_fraction']:.2f}%) |")


def swap_table(rows, motion, out):
    """ID switches and swaps (a marker taking another marker's track) per rig and clutter level,
    summed over seeds (issue 35 item 3: the swap rate per rig and clutter level)."""
    sel = [r for r in rows if r["motion"] == motion]
    if not sel:
        return
    rigs = sorted({r["rig"] for r in sel})
    clutters = sorted({r["clutter"] for r in sel}, key=float)
    print(f"{motion}: ID switches / swaps per rig (rows) and clutter blobs per frame (columns), seeds summed",
          file=out)
    print("| rig | " + " | ".join(f"c{c}" for c in clutters) + " |", file=out)
    print("| --- |" + " --- |" * len(clutters), file=out)
    for rig in rigs:
        cells = []
        for c in clutters:
            group = [r for r in sel if r["rig"] == rig and r["clutter"] == c]
            cells.append(f"{sum(r['id_switches'] for r in group)} / {sum(r.get('id_swaps', 0) for r in group)}"
                         if group else "-")
        print(f"| {rig} | " + " | ".join(cells) + " |", file=out)


def report(rows, out):
    print("| cell | RMSE mm | ID switches | of them swaps | coverage % | false records |", file=out)
    print("| --- | --- | --- | --- | --- | --- |", file=out)
    for r in rows:
        print(fmt(r), file=out)
    by = {
        "rmse_mm": max(rows, key=lambda r: r["rmse_mm"] or 0),
        "id_switches": max(rows, key=lambda r: r["id_switches"]),
        "coverage": min(rows, key=lambda r: r["coverage"]),
        "false_fraction": max(rows, key=lambda r: r["false_fraction"]),
    }
    for key, r in by.items():
        print(f"worst {key}: {r['cell']} ({r[key]})", file=out)
    rm = [r["rmse_mm"] for r in rows if r["rmse_mm"] is not None]
    print(f"median: RMSE {statistics.median(rm):.3f} mm, ID switches "
          f"{statistics.median(r['id_switches'] for r in rows)}, coverage "
          f"{100 * statistics.median(r['coverage'] for r in rows):.2f} %, false records "
          f"{100 * statistics.median(r['false_fraction'] for r in rows):.2f} %", file=out)
    for motion in MOTIONS:
        sel = [r for r in rows if r["motion"] == motion]
        if sel:
            rm = [r["rmse_mm"] for r in sel if r["rmse_mm"] is not None]
            print(f"{motion}: cells {len(sel)}, mean RMSE {statistics.mean(rm):.4f} mm, ID switches "
                  f"{sum(r['id_switches'] for r in sel)} (swaps {sum(r.get('id_swaps', 0) for r in sel)}), "
                  f"min coverage {100 * min(r['coverage'] for r in sel):.2f} %",
                  file=out)
    for motion in MOTIONS:
        swap_table(rows, motion, out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--bin", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--long", action="store_true", help="the full grid, 12 s scenes")
    p.add_argument("--cells", default=None, help="glob over rig/motion/clutter/seed names")
    p.add_argument("--duration", type=float, default=None)
    p.add_argument("--warmup", type=float, default=0.3)
    p.add_argument("--records-only", action="store_true",
                   help="judge only the instants the tracks file has records for (before stop 75); by default "
                        "every camera frame is judged, also those at which no track was published "
                        "(panoptes_eval --every-frame)")
    p.add_argument("--config", default=None, help="estimator configuration (default: none, the defaults)")
    p.add_argument("--json", default=None, help="write the rows here")
    p.add_argument("--blind", action="store_true", help="every camera looks away (checks the loud failure)")
    p.add_argument("--require-fast-id-switches", type=int, default=None,
                   help="club and ball cells: at most this many ID switches each")
    p.add_argument("--require-fast-coverage", type=float, default=None, help="club and ball cells: coverage at least")
    p.add_argument("--require-ball-coverage", type=float, default=None, help="ball cells: coverage at least")
    p.add_argument("--require-coverage", type=float, default=None, help="every cell: coverage at least")
    p.add_argument("--require-body-coverage", type=float, default=None,
                   help="walk, run and dance cells: coverage at least")
    p.add_argument("--require-max-false-fraction", type=float, default=None,
                   help="walk, run and dance cells: false record fraction at most")
    p.add_argument("--require-max-id-swaps", type=int, default=None,
                   help="every cell: at most this many ID swaps (two markers exchanging ids)")
    p.add_argument("--require-max-id-switches", type=int, default=None,
                   help="every cell: at most this many ID switches (a marker's track id changing)")
    args = p.parse_args()
    os.makedirs(args.work, exist_ok=True)
    if args.long or args.cells:
        cells = [(r, n, m, c, s) for (r, n) in RIGS for m in MOTIONS for c in CLUTTER for s in SEEDS]
    else:
        cells = CI_CELLS
    if args.cells:
        cells = [c for c in cells if fnmatch.fnmatch(cell_name(*c), args.cells)]
        if not cells:
            print(f"grid: no cell matches {args.cells}", file=sys.stderr)
            return 2
    rows, failures = [], []
    start = time.time()
    for c in cells:
        try:
            rows.append(run_cell(args, *c))
        except CellError as err:
            print(f"FAIL: {err}", file=sys.stderr)
            failures.append(str(err))
    report(rows, sys.stdout) if rows else None
    print(f"{len(rows)} cells in {time.time() - start:.1f} s")
    if args.json:
        json.dump(rows, open(args.json, "w"), indent=1)
    if failures:
        return 2
    bad = []
    for r in rows:
        fast = r["motion"] in ("club", "ball")
        if fast and args.require_fast_id_switches is not None and r["id_switches"] > args.require_fast_id_switches:
            bad.append(f"{r['cell']}: {r['id_switches']} ID switches > {args.require_fast_id_switches}")
        if fast and args.require_fast_coverage is not None and r["coverage"] < args.require_fast_coverage:
            bad.append(f"{r['cell']}: coverage {r['coverage']:.4f} < {args.require_fast_coverage}")
        if (r["motion"] == "ball" and args.require_ball_coverage is not None and
                r["coverage"] < args.require_ball_coverage):
            bad.append(f"{r['cell']}: coverage {r['coverage']:.4f} < {args.require_ball_coverage}")
        if (not fast and args.require_body_coverage is not None and
                r["coverage"] < args.require_body_coverage):
            bad.append(f"{r['cell']}: coverage {r['coverage']:.4f} < {args.require_body_coverage}")
        if args.require_coverage is not None and r["coverage"] < args.require_coverage:
            bad.append(f"{r['cell']}: coverage {r['coverage']:.4f} < {args.require_coverage}")
        if not fast and args.require_max_false_fraction is not None and r["false_fraction"] > args.require_max_false_fraction:
            bad.append(f"{r['cell']}: false records {r['false_fraction']:.4f} > {args.require_max_false_fraction}")
        if args.require_max_id_swaps is not None and r["id_swaps"] > args.require_max_id_swaps:
            bad.append(f"{r['cell']}: {r['id_swaps']} ID swaps > {args.require_max_id_swaps}")
        if args.require_max_id_switches is not None and r["id_switches"] > args.require_max_id_switches:
            bad.append(f"{r['cell']}: {r['id_switches']} ID switches > {args.require_max_id_switches}")
    for b in bad:
        print(f"FAIL: {b}", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
