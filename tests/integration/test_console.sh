#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The operator console (issue 18, docs/console.md) in Debian's chromium driven by playwright-core
# (tools/console/web/test/console_test.mjs) against a live simulated system: four
# camera_nodes (deploy/scenes/console.yaml: two loose markers and a body), estimator_node with the
# scene's calibration and bodies, panoptes_console. The browser checks the page; this script
# checks what the page showed against what each camera published (its own --out-features record):
# blob counts and positions, the threshold taking every blob away within 1 s and bringing them
# back, the mask rectangle and polygon removing the blobs inside them, a recording started and
# stopped from the page (panoptes_record --idle on the bus) written to disk, and the estimator
# killed and restarted. Screenshots go to $PANOPTES_CONSOLE_SHOTS (docs/).
source "$(dirname "$0")/lib.sh"
require_browser
scene="$source_dir/deploy/scenes/console.yaml"
shots="${PANOPTES_CONSOLE_SHOTS:-$work/shots}"
mkdir -p "$shots"
"$bin/panoptes_sim" calibration --scene "$scene" --out "$work/calibration.yaml" >/dev/null 2>&1 \
  && "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 0.1 >/dev/null 2>&1 \
  || { fail "simulate the console scene"; finish; }

estimator_command="'$bin/estimator_node' --calibration '$work/calibration.yaml' --bodies '$work/sim/bodies.yaml' --status-period 1"
# The first run's published poses (--out-poses: the same records as rt/panoptes/poses) to check the
# body figures the page showed against the pose of the stamp it showed.
bash -c "exec $estimator_command --out-poses '$work/poses.jsonl' --duration 150" >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
estimator_restart="$estimator_command --duration 90 >'$work/estimator2.log' 2>&1 & echo \$! >'$work/estimator2.pid'"
mkdir -p "$work/recordings"
"$bin/panoptes_record" --idle --id console_test --out "$work/recordings/default.mcap" --quiet >"$work/recorder.log" 2>&1 &
pids+=("$!")
for camera in cam0 cam1 cam2 cam3; do
  "$bin/camera_node" --source "sim:$scene#$camera" --duration 150 --out-features "$work/$camera.jsonl" --quiet \
    >"$work/$camera.log" 2>&1 &
  pids+=("$!")
done
printf 'console-test-%s\n' "$(head -c 12 /dev/urandom | od -An -tx1 | tr -d ' \n')" >"$work/token"
"$bin/panoptes_console" --bind 127.0.0.1:0 --token-file "$work/token" --url-file "$work/url" >"$work/console1.log" 2>&1 &
console=$!
pids+=("$console")
for _ in $(seq 50); do [ -s "$work/url" ] && break; sleep 0.1; done
url="$(cat "$work/url" 2>/dev/null)"
[ -n "$url" ] && pass "console serving at ${url%%\?*}" || { fail "console did not start: $(cat "$work/console1.log")"; finish; }
port="${url#http://127.0.0.1:}"; port="${port%%/*}"
restart="'$bin/panoptes_console' --bind 127.0.0.1:$port --token-file '$work/token' >'$work/console2.log' 2>&1 & echo \$! | tee '$work/console2.pid'"

expect_exit 2 "a token file with a short token is refused" -- "$bin/panoptes_console" --token-file <(echo short)
expect_stderr_contains "at least 16 characters" "the refusal names the rule"

start=$(date +%s)
node "$web/test/console_test.mjs" --url "$url" --out "$work/browser.json" --shots "$shots" \
  --console-pid "$console" --restart "$restart" --estimator-pid "$estimator" --estimator-restart "$estimator_restart" \
  --recorder console_test --recording-name take_console.mcap | tee "$work/browser.out"
rc=${PIPESTATUS[0]}
[ -s "$work/console2.pid" ] && pids+=("$(cat "$work/console2.pid")")
[ -s "$work/estimator2.pid" ] && pids+=("$(cat "$work/estimator2.pid")")
[ "$rc" -eq 0 ] && pass "browser checks ($(( $(date +%s) - start )) s)" || fail "browser checks (exit $rc)"

# The recording started and stopped from the page: on disk, next to the recorder's --out, a whole
# MCAP file (magic at both ends) of the size the page listed.
take="$work/recordings/take_console.mcap"
listed_bytes="$(/usr/bin/python3 -c 'import json,sys; r=json.load(open(sys.argv[1])).get("recording") or {}; print(r.get("bytes", -1))' "$work/browser.json")"
if [ -s "$take" ] && [ "$(head -c 8 "$take" | od -An -c | tr -d ' ')" = "211MCAP0\r\n" ] \
   && [ "$(tail -c 8 "$take" | od -An -c | tr -d ' ')" = "211MCAP0\r\n" ] && [ "$(stat -c %s "$take")" = "$listed_bytes" ]; then
  pass "the recording made from the page is a whole MCAP file of the listed size ($listed_bytes bytes)"
else
  fail "recording from the page: $take ($(stat -c %s "$take" 2>/dev/null || echo missing) bytes, listed $listed_bytes)"
fi

# What the page showed against what the cameras published.
for pid in "${pids[@]}"; do kill -INT "$pid" 2>/dev/null; done
sleep 1.5
/usr/bin/python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
result = json.load(open(f"{work}/browser.json"))
frames = {}
for camera in ("cam0", "cam1", "cam2", "cam3"):
    frames[camera] = {}
    for line in open(f"{work}/{camera}.jsonl"):
        record = json.loads(line)
        frames[camera][record["frame"]] = record
def report(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what)
    return ok
ok = True
matched = compared = worst = 0
for sample in result["samples"]:
    for camera in sample:
        record = frames[camera["id"]].get(camera["frame"])
        if record is None: continue
        compared += 1
        published = [(b["x"], b["y"]) for b in record["blobs"]]
        shown = [(b[0], b[1]) for b in camera["blobs"]]
        if len(published) == len(shown):
            matched += 1
            for sx, sy in shown:  # the page rounds to 0.01 px: nearest published blob
                worst = max(worst, min(max(abs(px - sx), abs(py - sy)) for px, py in published))
ok &= report(compared >= 30 and matched == compared and worst <= 0.006,
             f"page blobs = published blobs: {matched}/{compared} frames with the same count, worst position difference {worst:.4f} px")
# The body's figures against the pose the estimator published at the stamp the page showed. The
# page parses stamps as doubles (~256 ns steps at today's epoch): the nearest stamp within 1 us;
# poses of one body are >= 1 ms apart (60 Hz cameras, distinct phases). Figures are rounded to 0.1 mm.
shown = result.get("body_details")
if shown:
    same = [json.loads(line) for line in open(f"{work}/poses.jsonl")]
    same = [p for p in same if p["body"] == shown["name"] and abs(p["stamp_ns"] - shown["stamp_ns"]) <= 1000]
    offset = min((max(abs(a - b) for a, b in zip(p["p"], shown["position_m"])) for p in same), default=float("inf"))
    ok &= report(same and offset <= 0.0001,
                 f"body {shown['name']}'s figures = its published pose of stamp {shown['stamp_ns']} "
                 f"({len(same)} such pose(s), position within {1e3 * offset:.3f} mm)")
else:
    ok &= report(False, "the page showed no body figures")
cmd = result["commands"]
def window(camera, t0_ms, t1_ms):
    return [r for r in frames[camera].values() if t0_ms * 1e6 <= r["arrival_ns"] < t1_ms * 1e6]
if "threshold_max_ms" in cmd:
    # Up to 100 ms before the page noted the restore: it notes a command once sent, and the camera
    # can apply it first (a frame with blobs arrived 5 ms before the noted restore under ctest -j2).
    after = sorted(window("cam0", cmd["threshold_max_ms"], cmd["threshold_restore_ms"] - 100), key=lambda r: r["frame"])
    first_empty = next((r for r in after if not r["blobs"]), None)
    delay = (first_empty["arrival_ns"] / 1e6 - cmd["threshold_max_ms"]) if first_empty else float("inf")
    late = [r for r in after if r["arrival_ns"] / 1e6 > cmd["threshold_max_ms"] + 1000 and r["blobs"]]
    ok &= report(delay < 1000 and not late and len(after) > 30,
                 f"cam0 published no blob {delay:.0f} ms after threshold 255 (and {len(late)} frames with blobs "
                 f"after that second, of {len(after)})")
    back = window("cam0", cmd["threshold_restore_ms"] + 1000, cmd["threshold_restore_ms"] + 3000)
    ok &= report(back and all(r["blobs"] for r in back), f"cam0 publishes blobs again after the restore ({len(back)} frames)")
if cmd.get("mask_args"):
    _, x, y, w, h = (float(v) if i else v for i, v in enumerate(cmd["mask_args"]))
    # A blob lit pixels inside the mask if its bounding box ([x0, x1) x [y0, y1)) overlaps it; a
    # spot on the mask's edge keeps its outside pixels, and their refined centroid may lie up to a
    # pixel or two inside the edge.
    def overlaps(b):
        x0, y0, x1, y1 = b["bbox"]
        return x0 < x + w and x1 > x and y0 < y + h and y1 > y
    # Up to 100 ms before the page noted the clear, as for the threshold above (the camera applied a
    # clear to a frame that arrived 8 ms before the page noted it, in a quiet suite run).
    masked = window("cam1", cmd["mask_ms"] + 1000, cmd["clear_masks_ms"] - 100)
    inside = sum(1 for r in masked for b in r["blobs"] if overlaps(b))
    before = window("cam1", cmd["mask_ms"] - 3000, cmd["mask_ms"])
    had = sum(1 for r in before for b in r["blobs"] if overlaps(b))
    ok &= report(len(masked) > 10 and inside == 0 and had > 0,
                 f"cam1 published no blob with pixels inside the mask ({len(masked)} frames; {had} such blobs in the 3 s before)")
if cmd.get("polygon_args"):
    p = [float(v) for v in cmd["polygon_args"][1:]]
    corners = [(p[0], p[1]), (p[2], p[3]), (p[4], p[5])]
    def depth(x, y):  # distance inside the (convex) triangle, negative outside
        out = []
        for k in range(3):
            (ax, ay), (bx, by), (cx, cy) = corners[k], corners[(k + 1) % 3], corners[(k + 2) % 3]
            side = (bx - ax) * (y - ay) - (by - ay) * (x - ax)
            other = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
            out.append(side * (1 if other > 0 else -1) / ((bx - ax) ** 2 + (by - ay) ** 2) ** 0.5)
        return min(out)
    # Centroids deeper than 3 px: a spot on the edge keeps its outside pixels.
    masked = window("cam2", cmd["polygon_ms"] + 1000, cmd["clear_polygon_ms"] - 100)
    inside = sum(1 for r in masked for b in r["blobs"] if depth(b["x"], b["y"]) > 3)
    before = window("cam2", cmd["polygon_ms"] - 3000, cmd["polygon_ms"])
    had = sum(1 for r in before for b in r["blobs"] if depth(b["x"], b["y"]) > 3)
    ok &= report(len(masked) > 10 and inside == 0 and had > 0,
                 f"cam2 published no blob inside the polygon ({len(masked)} frames; {had} such blobs in the 3 s before)")
sys.exit(0 if ok else 1)
PY
[ $? -eq 0 ] && pass "the page agrees with what the cameras published" || fail "page against the cameras' records"
grep -q '"rate_limited"' "$work/console2.log" "$work/console1.log" 2>/dev/null; true
finish
