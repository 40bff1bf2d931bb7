#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The two bounds of the suite's time from one ctest run (docs/testing.md, "What bounds the suite's time").

    python3 tests/tools/suite_bounds.py CTEST_OUTPUT [--build build] [--jobs 2] [--top 12]

CTEST_OUTPUT is what `ctest` (or ./deploy/test.sh, or .ci/run) printed: each test's seconds are read
from its "Test #N: NAME ... Passed X sec" line. The locks come from the build's test properties
(`ctest --show-only=json-v1`), so the current tests/CMakeLists.txt decides which tests exclude each
other. Printed:
  chain  RUN_SERIAL tests + tests holding both live lanes + the longer of the two lanes (one after
         another: nothing shortens it but shorter tests or fewer locks);
  work   RUN_SERIAL tests (the other cores idle) + everything else shared by --jobs cores;
  real   ctest's "Total Test time (real)", for comparison: it is close to the larger bound.
"""
import argparse
import json
import re
import subprocess
import sys


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("log", help="ctest's output of a run")
    parser.add_argument("--build", default="build", help="build directory whose test properties apply (build)")
    parser.add_argument("--jobs", type=int, default=2, help="ctest -j of the run (2)")
    parser.add_argument("--top", type=int, default=12, help="longest tests to list (12)")
    args = parser.parse_args()

    seconds = {}
    real = None
    try:
        with open(args.log, encoding="utf-8", errors="replace") as log:
            for line in log:
                m = re.search(r"Test +#\d+: (.+?) \.{2,}.*?([0-9.]+) sec", line)
                if m:
                    seconds[m.group(1)] = float(m.group(2))
                m = re.search(r"Total Test time \(real\) = +([0-9.]+) sec", line)
                if m:
                    real = float(m.group(1))
    except OSError as error:
        sys.exit(f"suite_bounds.py: cannot read {args.log}: {error.strerror}")
    if not seconds:
        sys.exit(f"suite_bounds.py: {args.log} has no 'Test #N: NAME ... sec' lines (not a ctest output?)")
    shown = subprocess.run(["ctest", "--test-dir", args.build, "--show-only=json-v1"], capture_output=True, text=True)
    if shown.returncode != 0:
        sys.exit(f"suite_bounds.py: ctest --show-only in {args.build} failed: {shown.stderr.strip()}")
    kind = {}
    for test in json.loads(shown.stdout)["tests"]:
        props = {p["name"]: p["value"] for p in test.get("properties", [])}
        locks = set(props.get("RESOURCE_LOCK", []))
        if props.get("RUN_SERIAL"):
            kind[test["name"]] = "serial"
        elif {"live_a", "live_b"} <= locks:
            kind[test["name"]] = "both lanes"
        elif "live_a" in locks:
            kind[test["name"]] = "lane a"
        elif "live_b" in locks:
            kind[test["name"]] = "lane b"
    sums = {k: 0.0 for k in ("serial", "both lanes", "lane a", "lane b")}
    for name, s in seconds.items():
        if name in kind:
            sums[kind[name]] += s
    total = sum(seconds.values())
    chain = sums["serial"] + sums["both lanes"] + max(sums["lane a"], sums["lane b"])
    work = sums["serial"] + (total - sums["serial"]) / args.jobs
    print(f"{len(seconds)} tests, {total:.1f} s of test time; RUN_SERIAL {sums['serial']:.1f} s, both lanes "
          f"{sums['both lanes']:.1f} s, lane a {sums['lane a']:.1f} s, lane b {sums['lane b']:.1f} s")
    print(f"chain {chain:.1f} s, work {work:.1f} s (-j{args.jobs}), real {real if real is not None else '?'} s")
    print("longest:")
    for name, s in sorted(seconds.items(), key=lambda kv: -kv[1])[: args.top]:
        print(f"  {s:7.2f}  {name}  ({kind.get(name, 'free')})")


if __name__ == "__main__":
    main()
