#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""lint.bench_report's malformed records, in one process (each through report.sh was a Python start,
about 0.4 s, 1 s under the suite's load): every case breaks a copy of the committed results and
expects `bench_results.py report --check` to exit 2 with a message naming the file and the field.

Usage: bench_report_refusals.py <results dir> <doc> <work dir>; prints ok/FAIL lines, exits 1 on any
failure."""
import contextlib
import io
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
import bench_results  # noqa: E402

# (field the message must name, change to the first row of tracking.json; `data` is the whole file)
CASES = [
    ("date", 'del row["date"]'),
    ("date", 'row["date"] = "27.11.2026"'),
    ("value", 'row["value"] = "1.2 mm"'),
    ("commit", 'row["commit"] = "HEAD"'),
    ("goal.op", 'row["goal"]["op"] = "about"'),
    ("goal.source", 'del row["goal"]["source"]'),
    ("details", 'row["details"] = "estimator.md#no-such-heading"'),
    ("details", 'row["details"] = "nowhere.md"'),
    ("figure", 'row["figure"] = 1'),
    ("id", 'data["rows"][1]["id"] = row["id"]'),
    ("runs", 'row["runs"] = []'),
    ("date", 'row["value"] = None'),
]


def report_check(results, doc):
    """Runs `report --check` in this process: (exit code, stdout + stderr)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            rc = bench_results.main(["--results", results, "--doc", doc, "report", "--check"])
        except SystemExit as stop:  # argparse
            rc = stop.code
    return rc, out.getvalue().strip()


def main():
    results, doc, work = sys.argv[1:4]
    bad = os.path.join(work, "bad")
    failures = 0
    for field, change in CASES:
        shutil.rmtree(bad, ignore_errors=True)
        shutil.copytree(results, bad)
        path = os.path.join(bad, "tracking.json")
        with open(path) as f:
            data = json.load(f)
        row = data["rows"][0]  # noqa: F841 (used by the change)
        exec(change)
        with open(path, "w") as f:
            json.dump(data, f, indent=2, ensure_ascii=False)
        rc, out = report_check(bad, doc)
        if rc == 2 and path in out and f"field '{field}'" in out:
            print(f"ok: refused ({field}): {out}")
        else:
            print(f"FAIL: expected exit 2 naming {path} and field '{field}', got exit {rc}: {out}")
            failures += 1
    shutil.rmtree(bad, ignore_errors=True)
    shutil.copytree(results, bad)
    with open(os.path.join(bad, "broken.json"), "w") as f:
        f.write('{"capability": "x", "order": 99, "rows": [')
    rc, out = report_check(bad, doc)
    if rc == 2 and f"{bad}/broken.json: not valid JSON" in out:
        print("ok: a file that is not JSON is refused, named")
    else:
        print(f"FAIL: a file that is not JSON: expected exit 2 naming it, got exit {rc}: {out}")
        failures += 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
