#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Bodies from markers, live (issue 34 item 3, docs/bodies.md "Bodies from markers"): a simulated
# static object of four markers ("fixture") is seen as loose tracks by an estimator that knows only
# the moving bodies; panoptes_ctl body create --near its place makes a body of its four tracks and
# appends it to the bodies file the estimator runs with. The estimator reloads the file and tracks
# the new body within 1 s; its position is the object's true marker centroid within 0.1 mm and its
# rotation the identity (the object does not turn). Refusals: a track id not on the bus, fewer
# than 3 tracks, a name already defined (exit 2, naming them). The console the same way: a second
# static object ("fixture_b", another layout) is picked in the 3D view by shift+click in chromium
# (tools/console/web/test/console_body_test.mjs), named and created; the console runs body create,
# the estimator reloads the file and tracks it, and its pose is checked as the CLI's. The cameras
# and the estimator run until the CLI's and the browser's parts are done (at most 80 s), then stop
# on SIGINT: with a fixed 19 s, a slow machine's browser clicked Create after the estimator had
# ended (CI of stop 72: "no MocapFrame from an estimator within 5 s"); with 50 s, a run beside
# another test and a CPU hog reached Create as the cameras ended. About 25 s unloaded.
source "$(dirname "$0")/lib.sh"
scene="$work/scene.yaml"
python3 - "$source_dir/deploy/scenes/bodies.yaml" "$scene" <<'PY'
import sys
text = open(sys.argv[1]).read()
at = text.index("bodies:\n") + len("bodies:\n")
fixture = """  - name: fixture
    markers: [[0.0, 0.0, 0.0], [0.12, 0.0, 0.0], [0.03, 0.10, 0.0], [-0.04, 0.05, 0.07]]
    path: {type: static, position: [0.8, -0.6, 0.9]}
  - name: fixture_b
    markers: [[0.0, 0.0, 0.0], [0.10, 0.02, 0.0], [0.02, 0.13, 0.01], [0.05, -0.03, 0.09]]
    path: {type: static, position: [-0.6, 0.7, 1.1]}
"""
open(sys.argv[2], "w").write(text[:at] + fixture + text[at:])
PY
expect_exit 0 "simulate the scene with a static fixture" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 80
# The estimator knows the moving bodies only: the fixture's markers are loose tracks.
python3 - "$work/sim/bodies.yaml" "$work/live_bodies.yaml" <<'PY'
import sys, yaml
bodies = yaml.safe_load(open(sys.argv[1]))["bodies"]
yaml.safe_dump({"bodies": [b for b in bodies if not b["name"].startswith("fixture")]}, open(sys.argv[2], "w"))
PY
epoch=$(( ($(date +%s) + 3) * 1000000000 ))
"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$work/live_bodies.yaml" \
  --out-poses "$work/poses.jsonl" --duration 82 --status-period 1 >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
first_camera=${#pids[@]}
replay_cameras "$epoch" 80 c0 c1 c2 c3 c4 c5
cameras=("${pids[@]:first_camera}")
# The console with the same bodies file; its page picks fixture_b's tracks once they are
# confirmed and creates the body after the CLI's creation below ($work/cli_done).
browser=""
if have_browser "console part"; then
  shots="${PANOPTES_CONSOLE_SHOTS:-$work/shots}"
  mkdir -p "$shots"
  start_console body --bodies "$work/live_bodies.yaml" --calibration-dir "$work/console"
  timeout 90 node "$web/test/console_body_test.mjs" --url "$url" --out "$work/browser.json" --shots "$shots" \
    --near -0.6,0.7,1.1 --radius 0.2 --name fixture_b2 --after-file "$work/cli_done" >"$work/browser.out" 2>&1 &
  browser=$!
  pids+=("$browser")
fi
sleep 7
expect_exit 2 "a track that is not on the bus is refused" -- "$bin/panoptes_ctl" body create --name x --tracks 1,2,999999 \
  --bodies "$work/live_bodies.yaml"
# Tracks 1 and 2 are usually confirmed by now, but not always under load (once track 1 was not: the
# refusal then named "1,999999", rightly); the check is that 999999 is named with the tracks seen.
expect_stderr_contains "999999 on the bus (tracks seen: " "the refusal names the track and lists those seen"
expect_stderr_contains "no confirmed track " "the refusal says the tracks are not confirmed on the bus"
expect_exit 2 "a radius holding fewer than 3 tracks is refused" -- "$bin/panoptes_ctl" body create --name x \
  --near 0.8,-0.6,0.9 --radius 0.01 --bodies "$work/live_bodies.yaml"
expect_stderr_contains "at least 3 markers, got 1" "the refusal says how many"
expect_exit 0 "body create --near the fixture" -- "$bin/panoptes_ctl" body create --name fixture2 --near 0.8,-0.6,0.9 \
  --radius 0.2 --frames 30 --bodies "$work/live_bodies.yaml"
created_ns=$(date +%s%N)
cp "$work/last.out" "$work/created.json"
cat "$work/created.json"
touch "$work/cli_done"
expect_exit 2 "the same name again is refused" -- "$bin/panoptes_ctl" body create --name fixture2 --near 0.8,-0.6,0.9 \
  --radius 0.2 --bodies "$work/live_bodies.yaml"
expect_stderr_contains "a body named 'fixture2' is already defined" "the refusal names the body"
if [ -n "$browser" ]; then
  wait "$browser" && pass "console: $(grep -c '^PASS' "$work/browser.out") browser checks passed" ||
    fail "console body test: $(grep -v '^PASS' "$work/browser.out" | head -20)"
  grep '^PASS' "$work/browser.out" | sed 's/^/  /'
else
  sleep 2  # fixture2's first second of poses (checked below)
fi
kill -INT "${cameras[@]}" "$estimator" 2>/dev/null
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null
expect_clean_exit "$estimator" estimator_node "$work/estimator.log"
# Each created body: tracked within 1 s of its creation returning, its mean position at its
# object's true centroid within 0.1 mm, pose RMS within 0.3 mm where the estimator reports itself
# sure (position sigma <= 1 mm), and every pose within 4 sigma of the truth on each axis. On a
# loaded machine some cameras' frames can arrive late together for a while (once 5 of 6 for 150 ms:
# the body then rode on one camera along x, its x sigma grew to 40 mm and its position strayed
# 20 mm, all within 1.3 sigma; the late frames replayed it back); those poses say so in their sigma
# and are at most 5 % of the poses.
check_body() {  # NAME OBJECT CREATED_JSON CREATED_NS_OR_MS PLACE
  python3 - "$1" "$2" "$3" "$4" "$5" "$work/poses.jsonl" "$work/sim/bodies.yaml" <<'PY' &&
import json, math, sys, yaml
name, obj, created, created_ns, place, poses_file, bodies_file = sys.argv[1:]
created = json.loads(created)
assert created["body"] == name and len(created["tracks"]) == 4, created
truth = [b for b in yaml.safe_load(open(bodies_file))["bodies"] if b["name"] == obj][0]
place = [float(v) for v in place.split(",")]  # the object's static position in the scene
centroid = [place[i] + sum(m[i] for m in truth["markers"]) / len(truth["markers"]) for i in range(3)]
poses = [json.loads(line) for line in open(poses_file) if f'"{name}"' in line]
assert poses, f"no pose of {name}"
first = min(p["stamp_ns"] for p in poses)
created_ns = float(created_ns)
created_ns = created_ns * 1e6 if created_ns < 1e14 else created_ns  # the page's clock is in ms
delay = (first - created_ns) / 1e9
# The layout's error shows in the mean pose (the same for every frame of a static object); the
# estimator's own pose noise, which a body defined by hand has too, in the spread.
errors = [math.dist(p["p"], centroid) for p in poses]
sure = [e for p, e in zip(poses, errors) if max(p["sigma"][:3]) <= 1e-3]
unsure = len(poses) - len(sure)
mean = [sum(p["p"][i] for p in poses) / len(poses) for i in range(3)]
offset = math.dist(mean, centroid)
rms = math.sqrt(sum(e * e for e in sure) / max(len(sure), 1))
# The largest error on one axis in units of the reported sigma on that axis.
z = max(abs(p["p"][i] - centroid[i]) / max(p["sigma"][i], 1e-9) for p in poses for i in range(3))
angles = sorted(2 * math.degrees(math.acos(min(1.0, abs(p["q"][3])))) for p in poses)
print(f"{name}: {len(poses)} poses, first {delay * 1000:.0f} ms after its creation returned; mean position "
      f"{offset * 1000:.4f} mm from the true centroid, RMS {rms * 1000:.3f} mm over the {len(sure)} with sigma <= 1 mm, "
      f"largest {max(errors) * 1000:.3f} mm, largest error/sigma on an axis {z:.2f}, {unsure} with sigma > 1 mm; "
      f"rotation from the identity median {angles[len(angles) // 2]:.3f} deg")
# Where it strays, for the log of a failed run: the poses more than 1 mm off, with their times.
far = [(p["stamp_ns"], e) for p, e in zip(poses, errors) if e > 1e-3]
if far:
    print(f"{len(far)} poses more than 1 mm off, from {(far[0][0] - first) / 1e9:.3f} s to {(far[-1][0] - first) / 1e9:.3f} s "
          f"after the first: " + ", ".join(f"{(t - first) / 1e9:.3f} s {e * 1000:.1f} mm" for t, e in far[:12]))
assert delay <= 1.0, delay
assert offset <= 1e-4, offset
assert rms <= 3e-4, rms
assert z <= 4.0, z
assert unsure <= 0.05 * len(poses), unsure
PY
    pass "$1 tracked within 1 s, its mean position at the true centroid (<= 0.1 mm), RMS <= 0.3 mm where sure, every pose within 4 sigma" ||
    fail "$1 not tracked as expected"
}
check_body fixture2 fixture "$(tail -n 1 "$work/created.json")" "$created_ns" 0.8,-0.6,0.9
if [ -n "$browser" ]; then
  check_body fixture_b2 fixture_b "$(jq -c '.created' "$work/browser.json")" \
    "$(jq -r '.applied_ms' "$work/browser.json")" -0.6,0.7,1.1
fi
finish
