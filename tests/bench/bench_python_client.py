#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Throughput of the Python client (issue 15; docs/clients.md, "Python client: throughput and the
live test").

A child `bench_client --publish` writes MocapFrames (two tracked bodies, 8 labelled and 4 unlabelled
markers) at --rate for --duration seconds; this process reads them with panoptes.Client.wait_for_frame
and touches every body's position and orientation (NumPy arrays), as an application would. Prints
JSON: frames published / received / dropped (queue overflow) / missed (not delivered by the bus),
the per-frame cost on the Python thread (CPU time of that thread per frame: wait_for_frame, the
conversion and the attribute reads), the whole process's CPU per frame (with the library's receive
threads) and the publish -> Python latency. With --drain the frames are left queued while they are
published and read afterwards as fast as possible: the cost per frame without waiting.

    PANOPTES_DOMAIN=44 PYTHONPATH=build/python python3 tests/bench/bench_python_client.py --rate 1000
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

import panoptes


def percentiles(values_us):
    if not values_us:
        return None
    ordered = sorted(values_us)
    at = lambda q: round(ordered[int(q * (len(ordered) - 1))], 3)
    return {"p50_us": at(0.5), "p99_us": at(0.99), "max_us": round(ordered[-1], 3)}


def read_poses(frame):
    for body in frame.bodies:
        body.position, body.orientation  # what an application reads: two NumPy arrays per body


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--rate", type=float, default=1000.0, help="frames per second")
    parser.add_argument("--duration", type=float, default=10.0, help="seconds of publishing")
    parser.add_argument("--warmup", type=float, default=1.0, help="seconds of frames left out of the percentiles")
    parser.add_argument("--drain", action="store_true", help="read after publishing (queue holds every frame)")
    parser.add_argument("--publisher", default=str(pathlib.Path(__file__).resolve().parents[2] / "build/bin/bench_client"),
                        help="bench_client program")
    args = parser.parse_args()
    published = int(args.rate * args.duration)
    client = panoptes.Client(queue_depth=published + 16 if args.drain else 1024)
    publisher = subprocess.Popen([args.publisher, "--publish", "--rate", str(args.rate), "--duration", str(args.duration),
                                  "--readers", "1", "--domain", str(client.domain_id)], stderr=subprocess.PIPE)
    numbers, cost_us, latency_us = set(), [], []
    first = client.wait_for_frame(15.0)  # the publisher waits for this reader, then 0.5 s
    if first is None:
        sys.exit(f"bench_python_client: {client.status_text()} ({publisher.stderr.read().decode().strip()})")
    if args.drain:
        publisher.wait()
        time.sleep(0.5)
    cpu_start, thread_start, wall_start = time.process_time(), time.thread_time(), time.monotonic()
    read_poses(first)
    numbers.add(first.frame_number)
    received = 1
    skip = int(args.rate * args.warmup)  # frames left out of the percentiles
    timeout = 0 if args.drain else 1.0
    while True:
        before = time.thread_time_ns()
        frame = client.wait_for_frame(timeout)
        if frame is None:
            break
        read_poses(frame)
        if frame.frame_number > skip:
            cost_us.append((time.thread_time_ns() - before) * 1e-3)
            latency_us.append((time.time_ns() - frame.publish_ns) * 1e-3)
        numbers.add(frame.frame_number)
        received += 1
    frames = max(received - 1, 1)  # after the first
    idle_s = 0 if args.drain else 1.0  # the last wait, which timed out
    cpu_s, thread_s = time.process_time() - cpu_start, time.thread_time() - thread_start
    wall_s = time.monotonic() - wall_start - idle_s
    publisher.wait()
    stats = client.stats()
    client.close()
    print(json.dumps({
        "benchmark": "python_client_throughput", "mode": "drain" if args.drain else "live",
        "rate_hz": args.rate, "duration_s": args.duration, "frames_published": published,
        "frames_received": received, "frames_lost": published - len(numbers), "frames_dropped": stats.frames_dropped,
        "frames_missed": stats.frames_missed, "python": sys.version.split()[0],
        "python_thread_cpu_per_frame_us": round(thread_s / frames * 1e6, 2),
        "process_cpu_per_frame_us": round(cpu_s / frames * 1e6, 2),
        "process_cpu_percent_of_one_core": round(100 * cpu_s / wall_s, 1),
        "read_and_wait_thread_cpu": percentiles(cost_us),
        "publish_to_python_latency": percentiles(latency_us),
    }, indent=2))
    return 0 if published == len(numbers) and stats.frames_dropped == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
