#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The failed checks of the last ctest run, in a few lines at the very end of the output.

CI keeps only the tail of a run's output, where ctest names the failed tests but not what failed in
them (that is printed earlier, with --output-on-failure). deploy/test.sh calls this after a failed
run: for each failed test of Testing/Temporary/LastTest.log it prints the test's first FAIL lines
(or, without any, its last lines), each shortened, so the tail says what broke.

Usage: failure_digest.py BUILD_DIR [--lines-per-test N] [--width W]
"""
import argparse
import pathlib
import re
import sys


def test_outputs(log_text):
    """Yields (test name, output lines) per test block of a LastTest.log."""
    blocks = re.split(r"^(?=\d+/\d+ Testing: )", log_text, flags=re.M)
    for block in blocks:
        name = re.search(r"^\d+/\d+ Test: (\S+)", block, flags=re.M)
        if not name:
            continue
        body = block.split("Output:\n", 1)[-1]
        body = re.sub(r"^-{20,}\n", "", body, count=1, flags=re.M)
        body = body.split("<end of output>", 1)[0]
        yield name.group(1), body.splitlines()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build_dir")
    parser.add_argument("--lines-per-test", type=int, default=3, help="lines shown per failed test (default 3)")
    parser.add_argument("--width", type=int, default=200, help="characters per line (default 200)")
    args = parser.parse_args()
    log = pathlib.Path(args.build_dir) / "Testing" / "Temporary" / "LastTest.log"
    try:
        text = log.read_text(errors="replace")
    except OSError as error:
        print(f"failure digest: cannot read {log}: {error}")
        return 0
    # The failed tests as ctest lists them ("925:integration.test_live_labels"): a test expected to
    # fail (WILL_FAIL) or skipped is not "Test Passed." in the log but is not failed either.
    listed = log.with_name("LastTestsFailed.log")
    try:
        names = {line.split(":", 1)[1].strip() for line in listed.read_text().splitlines() if ":" in line}
    except OSError:
        names = set()
    failed = [(name, lines) for name, lines in test_outputs(text) if name in names]
    if not failed:
        return 0
    print(f"failure digest ({len(failed)} failed test(s); full output above and in {log}):")
    for name, lines in failed:
        picked = [line for line in lines if line.startswith("FAIL") or "[  FAILED  ]" in line or "Failure" in line]
        picked = picked[: args.lines_per_test] or [line for line in lines if line.strip()][-args.lines_per_test:]
        for line in picked or ["(no output)"]:
            line = line.strip()
            if len(line) > args.width:
                line = line[: args.width - 3] + "..."
            print(f"  {name}: {line}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
