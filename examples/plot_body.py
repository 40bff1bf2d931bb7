#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plots a body's position live from Panoptes (matplotlib; docs/clients.md).

    PYTHONPATH=build/python python3 examples/plot_body.py --body head
    PYTHONPATH=build/python python3 examples/plot_body.py --body head --duration 10 --save head.png

With --save it runs headless (Agg backend): reads for --duration seconds, then writes the plot.
Exits 1 when no estimator answers within --timeout or the body is unknown, 2 on bad arguments.
"""
import argparse
import sys
import time

import matplotlib

import panoptes


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                     formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("--body", default=None, help="body name (default: the estimator's first body)")
    parser.add_argument("--duration", type=float, default=0.0, help="seconds to plot (0: until the window closes)")
    parser.add_argument("--save", default=None, help="write the plot to this PNG file instead of showing it")
    parser.add_argument("--window", type=float, default=10.0, help="seconds of history shown")
    parser.add_argument("--timeout", type=float, default=5.0, help="give up when no frame arrives this long")
    parser.add_argument("--domain", type=int, default=None, help="DDS domain (default: $PANOPTES_DOMAIN, else 0)")
    parser.add_argument("--profile", default=None, help="DDS XML profile (default: the installed loopback.xml)")
    args = parser.parse_args()
    if args.save and args.duration <= 0:
        parser.error("--save needs --duration > 0")
    if args.duration < 0 or args.timeout <= 0 or args.window <= 0:
        parser.error("--duration must be >= 0, --timeout and --window > 0")
    return args


def main():
    args = parse_arguments()
    if args.save:
        matplotlib.use("Agg")  # headless: no display needed
    import matplotlib.pyplot as plt  # after the backend is chosen
    try:
        client = panoptes.Client(profile=args.profile, domain=args.domain)
    except panoptes.ClientError as error:
        print(f"plot_body: {error}", file=sys.stderr)
        return 1
    with client:
        names = [b.name for b in client.wait_for_descriptions(args.timeout) or []]  # with the first frames
        args.body = args.body or next(iter(names), None)
        if args.body not in names:
            print(f"plot_body: no body '{args.body}' (described: {', '.join(names) or 'none'}); "
                  f"{client.status_text()} on domain {client.domain_id}", file=sys.stderr)
            return 1
        figure, axes = plt.subplots()
        lines = [axes.plot([], [], label=axis)[0] for axis in "xyz"]
        axes.set_xlabel("time (s)")
        axes.set_ylabel("position (m, world)")
        times, points, start_ns, drawn = [], [], None, time.monotonic()
        end = time.monotonic() + args.duration if args.duration > 0 else float("inf")
        while time.monotonic() < end and (args.save or plt.fignum_exists(figure.number)):
            frame = client.wait_for_frame(args.timeout)
            body = frame.body(args.body) if frame is not None else None
            if body is None:  # no frame in time, or the bodies file changed
                print(f"plot_body: no '{args.body}': {client.status_text()} on domain {client.domain_id} "
                      "(is estimator_node running?)", file=sys.stderr)
                return 1
            start_ns = start_ns or frame.stamp_ns
            if body.tracking_valid:
                times.append((frame.stamp_ns - start_ns) * 1e-9)
                points.append(body.position.tolist())
            if not args.save and time.monotonic() - drawn > 0.1:  # redraw at 10 Hz; frames queue meanwhile
                draw(axes, lines, times, points, args.body, args.window)
                plt.pause(0.001)
                drawn = time.monotonic()
        draw(axes, lines, times, points, args.body, args.window if not args.save else None)
        if args.save:
            figure.savefig(args.save, dpi=100)
            print(f"plot_body: {len(points)} positions of '{args.body}' plotted to {args.save} "
                  f"(panoptes {panoptes.__version__})", file=sys.stderr)
    return 0


def draw(axes, lines, times, points, name, window):
    first = 0  # the points of the last `window` seconds (all if None)
    if window is not None and times:
        first = next(i for i, t in enumerate(times) if t >= times[-1] - window)
    for k, line in enumerate(lines):
        line.set_data(times[first:], [p[k] for p in points[first:]])
    axes.set_title(f"{name}: {len(points)} positions")
    axes.relim()
    axes.autoscale_view()
    axes.legend(loc="upper right")


if __name__ == "__main__":
    sys.exit(main())
