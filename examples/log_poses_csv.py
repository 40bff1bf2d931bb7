#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Logs every body pose Panoptes publishes to CSV, one row per body per frame (docs/clients.md).

    PYTHONPATH=build/python python3 examples/log_poses_csv.py --duration 10 --out poses.csv

Columns: frame, stamp_ns (mid-exposure capture time, ns), body, x, y, z (m, world), qx, qy, qz, qw
(body -> world), valid (1 if tracked). Floats are written exactly (shortest repr that reads back to
the same double). Exits 1 when no estimator answers within --timeout, 2 on bad arguments.
"""
import argparse
import csv
import sys
import time

import panoptes

COLUMNS = ["frame", "stamp_ns", "body", "x", "y", "z", "qx", "qy", "qz", "qw", "valid"]


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--out", default="-", help="CSV file to write ('-': standard output)")
    parser.add_argument("--duration", type=float, default=10.0, help="seconds to log (0: until Ctrl-C)")
    parser.add_argument("--timeout", type=float, default=5.0,
                        help="give up when no frame arrives for this many seconds")
    parser.add_argument("--domain", type=int, default=None, help="DDS domain (default: $PANOPTES_DOMAIN, else 0)")
    parser.add_argument("--profile", default=None,
                        help="DDS XML profile (default: $PANOPTES_DDS_PROFILE, else the installed loopback.xml)")
    args = parser.parse_args()
    if args.duration < 0:
        parser.error(f"--duration {args.duration}: must be >= 0")
    if args.timeout <= 0:
        parser.error(f"--timeout {args.timeout}: must be > 0")
    return args


def log(client, writer, duration, timeout):
    """Writes rows until `duration` seconds passed; returns (frames, rows), or None without data."""
    frames = rows = 0
    end = time.monotonic() + duration if duration > 0 else float("inf")
    while time.monotonic() < end:
        frame = client.wait_for_frame(timeout)
        if frame is None:
            return None
        frames += 1
        for body in frame.bodies:
            writer.writerow([frame.frame_number, frame.stamp_ns, body.name, *body.position.tolist(),
                             *body.orientation.tolist(), int(body.tracking_valid)])
            rows += 1
    return frames, rows


def main():
    args = parse_arguments()
    try:
        client = panoptes.Client(profile=args.profile, domain=args.domain)
    except panoptes.ClientError as error:
        print(f"log_poses_csv: {error}", file=sys.stderr)
        return 1
    out = sys.stdout if args.out == "-" else open(args.out, "w", newline="", encoding="utf-8")
    with client, out:
        writer = csv.writer(out)
        writer.writerow(COLUMNS)
        try:
            counts = log(client, writer, args.duration, args.timeout)
        except KeyboardInterrupt:
            counts = (client.stats().frames_received, None)
        if counts is None:
            print(f"log_poses_csv: {client.status_text()} on domain {client.domain_id} "
                  "(is estimator_node running?)", file=sys.stderr)
            return 1
        rate = client.frame_rate()
        print(f"log_poses_csv: frames at {rate.hz:.2f} Hz "
              f"({'fixed rate' if rate.fixed else 'one per processed camera frame'})", file=sys.stderr)
        newest = client.latest()
        timecode = client.timecode(newest) if newest is not None else None  # fixed-rate frames only
        if timecode is not None:
            print(f"log_poses_csv: the newest frame's timecode {timecode.text} ({timecode.rate_hz} frames a second)",
                  file=sys.stderr)
        print(f"log_poses_csv: {counts[0]} frames logged to {args.out} (panoptes {panoptes.__version__}); "
              f"{client.stats()}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
