#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# Where the zero-wait outputs of a late-delivery run lose accuracy (issue 16; docs/estimator.md,
# "Replay cost"). The outputs of `estimator_node --replay-arrival` are split into those
# published when every older frame had arrived ("complete") and those published while older frames
# were still in flight, and each record is compared with the in-order run's record of the same
# stamp and id. Exact replay: every complete record is identical.
#   zero_wait_outputs.py FEATURE_DIR IN_ORDER_TRACKS.jsonl ARRIVAL_ORDER_TRACKS.jsonl
import json, sys, glob, math, collections
late_dir, in_order_tracks, late_tracks = sys.argv[1], sys.argv[2], sys.argv[3]
frames = []
for path in glob.glob(late_dir + "/cam*.jsonl"):
    for line in open(path):
        f = json.loads(line)
        if "stamp_ns" not in f: continue
        frames.append((f["stamp_ns"], f.get("camera_id", path), f.get("frame", 0), f.get("received_ns", f["stamp_ns"])))
frames.sort(key=lambda f: (f[0], f[1], f[2]))
order = sorted(range(len(frames)), key=lambda i: frames[i][3])  # stable
arrived = [False] * len(frames)
oldest_missing = 0  # index in stamp order of the oldest frame not yet arrived
newest = -1
missing_at = {}  # output stamp -> number of older frames in flight
for i in order:
    arrived[i] = True
    while oldest_missing < len(frames) and arrived[oldest_missing]: oldest_missing += 1
    stamp = frames[i][0]
    if stamp >= newest:
        newest = stamp
        n = 0
        k = oldest_missing
        while k < len(frames) and frames[k][0] < stamp:
            if not arrived[k]: n += 1
            k += 1
        missing_at[stamp] = n
def load(path):
    d = {}
    for line in open(path):
        r = json.loads(line)
        d[(r["stamp_ns"], r["id"])] = r["p"]
    return d
a = load(in_order_tracks); b = load(late_tracks)
groups = collections.defaultdict(lambda: [0, 0, 0.0, 0])  # records, matched, sum d², identical
for (stamp, tid), p in b.items():
    n = missing_at.get(stamp)
    key = "complete" if n == 0 else ("in flight" if n is not None else "unknown")
    g = groups[key]; g[0] += 1
    q = a.get((stamp, tid))
    if q is None: continue
    d2 = sum((x - y) ** 2 for x, y in zip(p, q))
    g[1] += 1; g[2] += d2; g[3] += d2 < 1e-18
outs = collections.Counter("complete" if n == 0 else "in flight" for n in missing_at.values())
print("outputs:", dict(outs), "mean frames in flight when not complete: %.2f" %
      (sum(n for n in missing_at.values() if n) / max(1, outs["in flight"])))
for key, (n, m, s, same) in groups.items():
    print("%-10s records %7d matched %7d identical %7d rms diff to in-order %.4f mm" % (key, n, m, same, 1e3 * math.sqrt(s / max(m, 1))))
