#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The console's calibration page (issue 18, docs/console.md "Calibration") in Debian's chromium
# driven by playwright-core (tools/console/web/test/console_calibration_test.mjs): the
# page starts a wand capture, six camera_nodes replay the simulated wand room (as
# test_calibration_capture.sh), the page shows each camera's 8x8 coverage live, stops the capture,
# runs the solve and shows its report (per-camera residuals, wand-length statistics, the plots),
# then captures the wand laid on the floor at four places (test_calibration.sh's floor recording)
# and sets the world frame. This script then checks the page's figures against the solve's own
# report.json and the world frame's summary.
source "$(dirname "$0")/lib.sh"
require_browser
shots="${PANOPTES_CONSOLE_SHOTS:-$work/shots}"
mkdir -p "$shots"
cp "$source_dir/deploy/scenes/wand_room.yaml" "$work/room.yaml"
"$bin/panoptes_sim" features --scene "$work/room.yaml" --out-dir "$work/wand" --duration 6 >/dev/null 2>&1 ||
  { fail "simulate the wand room"; finish; }
floor_recording floor \
  "[0.25, 0, 0.007], [0.25, 0, 0.007], [-0.8, 0.5, 0.007], [-0.8, 0.5, 0.007], [0.9, 0.8, 0.007], [0.9, 0.8, 0.007], [-0.5, -0.9, 0.007], [-0.5, -0.9, 0.007]" \
  "[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0.564642, 0.825336], [0, 0, 0.564642, 0.825336], [0, 0, -0.29552, 0.955336], [0, 0, -0.29552, 0.955336], [0, 0, 0.841471, 0.540302], [0, 0, 0.841471, 0.540302]"

printf 'calibration-test-%s\n' "$(head -c 12 /dev/urandom | od -An -tx1 | tr -d ' \n')" >"$work/token"
"$bin/panoptes_console" --bind 127.0.0.1:0 --token-file "$work/token" --url-file "$work/url" \
  --calibration-dir "$work/cal" --calibration-cameras "$work/wand/calibration.yaml" >"$work/console.log" 2>&1 &
pids+=("$!")
for _ in $(seq 50); do [ -s "$work/url" ] && break; sleep 0.1; done
url="$(cat "$work/url" 2>/dev/null)"
[ -n "$url" ] && pass "console serving at ${url%%\?*}" || { fail "console did not start: $(cat "$work/console.log")"; finish; }

# The cameras start once the page's capture runs; they replay a recording (wand/ or floor/) from a
# common epoch 3 s ahead (a whole second 3-4 s ahead until stop 71). With 2 s, six camera_nodes
# starting on a loaded 2-core machine began up to 1.7 s after the epoch and missed the floor
# recording's first placement (issue 37).
cat >"$work/cameras.sh" <<SH
epoch=\$(( \$(date +%s%N) + 3000000000 ))
for camera in cam0 cam1 cam2 cam3 cam4 cam5; do
  '$bin/camera_node' --source "features:$work/\$1/\$camera.jsonl" --sim-epoch-ns "\$epoch" --duration "\$2" --quiet \
    >'$work/'\$1_\$camera.log 2>&1 &
  echo \$! >>'$work/camera.pids'
done
wait
SH
start=$(date +%s)
node "$web/test/console_calibration_test.mjs" --url "$url&view=calibration" --out "$work/browser.json" --shots "$shots" \
  --cameras "bash '$work/cameras.sh' wand 11" --floor-cameras "bash '$work/cameras.sh' floor 13" --wand 0,0.18,0.5 \
  | tee "$work/browser.out"
rc=${PIPESTATUS[0]}
[ -s "$work/camera.pids" ] && while read -r pid; do pids+=("$pid"); done <"$work/camera.pids"
[ "$rc" -eq 0 ] && pass "browser checks ($(( $(date +%s) - start )) s)" || fail "browser checks (exit $rc)"

[ -s "$work/cal/wand.jsonl" ] && pass "the page's capture wrote $(grep -c . "$work/cal/wand.jsonl") frames" ||
  fail "no capture file in $work/cal"
/usr/bin/python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
page = json.load(open(f"{work}/browser.json"))
report = json.load(open(f"{work}/cal/calibration.report.json"))
def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what)
    return ok
ok = check(all(c["calibrated"] for c in report["cameras"]) and len(report["cameras"]) == 6,
           "report.json: 6 of 6 cameras calibrated")
shown = {row["camera"]: row for row in page.get("report_rows", [])}
same = all(c["id"] in shown and shown[c["id"]]["observations"] == str(c["observations"]) and
           shown[c["id"]]["median"] == f'{c["raw_frame_error_2d_px"]["all"]["median_px"]:.3f}' for c in report["cameras"])
ok &= check(same, "the page's table shows the report's observations and raw median per camera")
world = open(f"{work}/cal/calibration.world.txt").read()
ok &= check("4 placements" in world and page.get("world_text", "").strip() == world.strip(),
            "the world frame from the wand on the floor (4 placements) is shown as calibration.world.txt says")
# The CLI's own summary: "  cam0: 600 frames, 600 with blobs, 0 missing, image coverage 37%".
import re
cli = {m[0]: [int(m[3]), int(m[1]), int(m[2])] for m in
       re.findall(r"^  (\S+): (\d+) frames, (\d+) with blobs, \d+ missing, image coverage (\d+)%", open(f"{work}/cal/capture.log").read(), re.M)}
coverage = page.get("coverage", {})
ok &= check(len(coverage) == 6 and coverage == cli,
            f"the page's coverage (percent, frames, with blobs) equals what calibrate capture printed: {coverage}")
sys.exit(0 if ok else 1)
PY
[ $? -eq 0 ] && pass "the page agrees with the solve's report" || fail "page against report.json"
finish
