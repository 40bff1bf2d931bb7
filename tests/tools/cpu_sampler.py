#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Where the CPU goes during a multi-process test (issue 37: the 32-camera scale test).

    cpu_sampler.py --out FILE.json --seconds S --group NAME=PID[,PID...] [--group ...] [--threads PID]

Samples /proc every --period seconds (1) for --seconds: each group's CPU (utime + stime of its
processes, as a percentage of one core), the machine's busy share of all cores and its run queue
(procs_running in /proc/stat), and, for --threads PID, that process's CPU per thread name. Writes
one JSON document: per-second series and the whole window's means. Processes that exit are counted
until they exit. Reads only /proc: no pidstat needed.
"""
import argparse
import json
import os
import time

TICKS = os.sysconf("SC_CLK_TCK")


def process_ticks(pid, path="stat"):
    try:
        with open(f"/proc/{pid}/{path}") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])  # utime, stime (fields 14, 15 of proc(5))
    except (OSError, IndexError, ValueError):
        return None


def thread_ticks(pid):
    out = {}
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tids:
        try:
            with open(f"/proc/{pid}/task/{tid}/comm") as comm:
                name = comm.read().strip()
        except OSError:
            continue
        ticks = process_ticks(pid, f"task/{tid}/stat")
        if ticks is not None:
            out[f"{name}#{tid}"] = ticks
    return out


def machine():
    with open("/proc/stat") as stat:
        lines = stat.read().splitlines()
    cpu = [int(v) for v in lines[0].split()[1:]]
    idle = cpu[3] + cpu[4]  # idle + iowait
    running = next(int(line.split()[1]) for line in lines if line.startswith("procs_running"))
    return sum(cpu), idle, running


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", required=True)
    parser.add_argument("--seconds", type=float, required=True)
    parser.add_argument("--period", type=float, default=1.0)
    parser.add_argument("--group", action="append", default=[], help="NAME=PID[,PID...]")
    parser.add_argument("--threads", type=int, help="a process whose threads are reported by name")
    args = parser.parse_args()
    groups = {}
    for spec in args.group:
        name, _, pids = spec.partition("=")
        groups[name] = [int(p) for p in pids.split(",") if p]
    last = {pid: process_ticks(pid) for pids in groups.values() for pid in pids}
    last_threads = thread_ticks(args.threads) if args.threads else {}
    total0, idle0, _ = machine()
    last_machine = (total0, idle0)
    start = time.monotonic()
    series = []
    thread_sum = {}
    group_sum = {name: 0 for name in groups}
    while time.monotonic() - start < args.seconds:
        time.sleep(args.period)
        now = {pid: process_ticks(pid) for pid in last}
        total, idle, running = machine()
        elapsed_ticks = (total - last_machine[0]) / os.cpu_count()  # ticks of one core
        sample = {"t": round(time.monotonic() - start, 1), "run_queue": running,
                  "machine_busy_percent": round(100.0 * (1 - (idle - last_machine[1]) / max(1, total - last_machine[0])), 1)}
        for name, pids in groups.items():
            used = sum(now[p] - last[p] for p in pids if now[p] is not None and last[p] is not None)
            group_sum[name] += used
            sample[name] = round(100.0 * used / max(1.0, elapsed_ticks), 1)
        if args.threads:
            threads = thread_ticks(args.threads)
            for key, ticks in threads.items():
                if key in last_threads:
                    base = key.split("#")[0]
                    thread_sum[base] = thread_sum.get(base, 0) + ticks - last_threads[key]
            last_threads = threads
        series.append(sample)
        last = {pid: (now[pid] if now[pid] is not None else last[pid]) for pid in last}
        last_machine = (total, idle)
    seconds = time.monotonic() - start
    summary = {
        "seconds": round(seconds, 1), "cores": os.cpu_count(),
        "percent_of_one_core": {name: round(100.0 * ticks / TICKS / seconds, 1) for name, ticks in group_sum.items()},
        "machine_busy_percent_mean": round(sum(s["machine_busy_percent"] for s in series) / max(1, len(series)), 1),
        "run_queue_mean": round(sum(s["run_queue"] for s in series) / max(1, len(series)), 1),
        "threads_percent_of_one_core": {name: round(100.0 * ticks / TICKS / seconds, 1)
                                        for name, ticks in sorted(thread_sum.items(), key=lambda kv: -kv[1])},
        "series": series,
    }
    with open(args.out, "w") as out:
        json.dump(summary, out)


if __name__ == "__main__":
    main()
