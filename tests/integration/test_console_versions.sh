#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The versions of the estimator's calibration file on the console's calibration page (issue 36
# item 5: "an operator can accept or revert a change from the console"; docs/console.md, "Versions
# of the calibration"). The shell makes three versions with the CLI (the file as it was, a hand
# edit of cam1's pose, a revert to the first); panoptes_console --calibration serves the page, and
# Debian's chromium driven by playwright-core (tools/console/web/test/console_versions_test.mjs)
# reverts to the hand edit, accepts that revert, and sends a version that does not exist. Checks
# here: the file then holds the hand edit's exact bytes, and the CLI's history agrees with the page.
# (That a running estimator_node takes the reverted file is test_continuous_calibration's.)
source "$(dirname "$0")/lib.sh"
require_browser
en="$bin/estimator_node"
shots="${PANOPTES_CONSOLE_SHOTS:-$work/shots}"
mkdir -p "$shots"
expect_exit 0 "the console scene's calibration" -- "$bin/panoptes_sim" calibration \
  --scene "$source_dir/deploy/scenes/console.yaml" --out "$work/cal.yaml"
expect_exit 0 "calibrate history --start (v1)" -- "$en" calibrate history --calibration "$work/cal.yaml" --start
# A hand edit: cam1 moved by 2 mm along x (its first 't:' line).
python3 - "$work/cal.yaml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
at = text.index('id: "cam1"')
match = re.compile(r"t: \[([-0-9.e]+),").search(text, at)
value = float(match.group(1)) + 0.002
open(sys.argv[1], "w").write(text[:match.start(1)] + repr(value) + text[match.end(1):])
PY
cp "$work/cal.yaml" "$work/edited.yaml"
expect_exit 0 "calibrate revert --version 1 (stores the hand edit as v2, the revert as v3)" -- \
  "$en" calibrate revert --calibration "$work/cal.yaml" --version 1

start_console versions --calibration "$work/cal.yaml" --calibration-dir "$work/console"
node "$web/test/console_versions_test.mjs" --url "$url" --out "$work/browser.json" --shots "$shots" \
  --versions 3 --revert 2 >"$work/browser.out" 2>&1
rc=$?
cat "$work/browser.out"
[ "$rc" -eq 0 ] && pass "the page's versions checks" || fail "the page's versions checks (exit $rc)"

cmp -s "$work/cal.yaml" "$work/edited.yaml" && pass "the page's revert restored the hand edit's exact bytes" ||
  fail "the file is not the hand edit after the page's revert"
expect_exit 0 "calibrate history --json" -- "$en" calibrate history --calibration "$work/cal.yaml" --json
python3 - "$work/last.out" <<'PY' && pass "the history: v4 'revert to 2' (cam1) accepted, v3 reverted" ||
import json, sys
v = {x["version"]: x for x in (json.loads(line) for line in open(sys.argv[1]) if line.strip())}
print({k: (x["reason"], x["state"], x["cameras"]) for k, x in v.items()})
sys.exit(0 if len(v) == 4 and v[4]["reason"] == "revert to 2" and v[4]["state"] == "accepted"
         and v[4]["cameras"] == ["cam1"] and v[3]["state"] == "reverted" else 1)
PY
  fail "history after the page's revert and accept"
finish
