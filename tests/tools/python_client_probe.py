#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Records what a panoptes.Client (the Python package) receives as JSON lines, for
tests/integration/test_client.sh: one line per frame (floats as float.hex(), exact), one per
change of the body descriptions, the Stats at the end. The client is never restarted."""
import argparse
import json
import sys
import time

import panoptes


def hexes(array):
    return [float(v).hex() for v in array]


def frame_line(frame):
    bodies = [{"name": b.name, "id": b.id, "valid": b.tracking_valid, "p": hexes(b.position),
               "q": hexes(b.orientation), "v": hexes(b.linear_velocity), "w": hexes(b.angular_velocity),
               "sigma": hexes(b.sigma), "horizon_ns": b.prediction_horizon_ns} for b in frame.bodies]
    return {"type": "frame", "frame": frame.frame_number, "stamp_ns": frame.stamp_ns,
            "receive_ns": frame.receive_ns, "bodies": bodies, "markers": len(frame.markers),
            "unlabelled": len(frame.unlabelled_markers()), "labelled": sum(m.labelled for m in frame.markers)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--duration", type=float, required=True)
    args = parser.parse_args()
    descriptions_seen = 0
    with panoptes.Client() as client, open(args.out, "w", encoding="utf-8") as out:
        end = time.monotonic() + args.duration
        while time.monotonic() < end:
            frame = client.wait_for_frame(0.1)
            if frame is not None:
                out.write(json.dumps(frame_line(frame)) + "\n")
            stats = client.stats()
            if stats.descriptions_received != descriptions_seen:
                descriptions_seen = stats.descriptions_received
                bodies = [{"name": d.name, "id": d.id, "kind": d.kind, "markers": d.markers.tolist()}
                          for d in client.body_descriptions()]
                described = {d["name"]: repr(client.body_description(d["name"])) for d in bodies}
                out.write(json.dumps({"type": "descriptions", "bodies": bodies, "repr": described}) + "\n")
        stats = client.stats()
        out.write(json.dumps({"type": "stats", **{k: getattr(stats, k) for k in dir(stats) if not k.startswith("_")}})
                  + "\n")
        print(f"python_client_probe: {client.status_text()}; {stats}", file=sys.stderr)


if __name__ == "__main__":
    main()
