#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The ROS 2 topics live (issue 15, docs/ros2.md): estimator_node on the clients scene (two bodies,
# two loose markers, six cameras) publishes rt/panoptes/<body>/pose and twist, rt/tf,
# rt/rigid_bodies and rt/markers; panoptes_ros2_probe reads every topic with a best-effort (ROS 2
# SensorDataQoS) and a reliable (ROS 2 default QoS) reader. Checks: both readers receive every topic;
# stamps are the capture stamps of the estimator's own poses and its values bit for bit; frame ids,
# tf child frames, marker names and id types, frame numbers; poses agree with the simulator's truth;
# the ros2: configuration keys and --no-ros2 take effect; /tf at its rate limit (ros2.tf_rate_hz) +-5 %
# in both frame modes; --ros2-namespace puts every ROS 2 topic but /tf under the namespace and
# nothing under the bare names (issue 34 item 7).
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/clients.yaml"
expect_exit 0 "simulate the clients scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"

# run_live NAME SECONDS ESTIMATOR-ARGS...: six cameras for SECONDS (camera_node --duration, from their
# start; the scene's epoch is 2-3 s after it), estimator_node, the probe and the recorder until 0.5 s
# after the last camera ended (they ran 2-3 s more until stop 79, 5 s until issue 31; the checks
# below judge what was published while the cameras ran, which reaches the probe within milliseconds).
run_live() {
  local name="$1" seconds="$2"
  shift 2
  epoch=$(( ($(date +%s) + 3) * 1000000000 ))
  "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$work/sim/bodies.yaml" \
    --out-poses "$work/$name.poses.jsonl" --duration $((seconds + 3)) --quiet "$@" >"$work/$name.log" 2>&1 &
  local estimator=$!
  pids+=("$estimator")
  "$bin/panoptes_ros2_probe" --out "$work/$name.ros2.jsonl" --body head --body tool --duration $((seconds + 3)) \
    "${probe_args[@]}" >"$work/$name.probe.log" 2>&1 &
  local probe=$!
  pids+=("$probe")
  local recorder=""
  if [ "${#record_topics[@]}" -gt 0 ]; then  # also panoptes_record: its default topics ("all") or these
    local topic_args=()
    for topic in "${record_topics[@]}"; do [ "$topic" = all ] || topic_args+=(--topics "$topic"); done
    "$bin/panoptes_record" --out "$work/$name.mcap" --duration $((seconds + 2)) --quiet ${topic_args[@]+"${topic_args[@]}"} \
      >"$work/$name.record.log" 2>&1 &
    recorder=$!
    pids+=("$recorder")
  fi
  local cameras=()
  for camera in c0 c1 c2 c3 c4 c5; do
    "$bin/camera_node" --source "features:$work/sim/$camera.jsonl" --sim-epoch-ns "$epoch" --duration "$seconds" \
      --quiet >"$work/$name.$camera.log" 2>&1 &
    pids+=("$!")
    cameras+=("$!")
  done
  # The estimator, the probe and the recorder end 0.5 s after the last camera (SIGINT: the same
  # summary and files as at the end of their --duration, which stays as a bound).
  for camera in "${cameras[@]}"; do timeout $((seconds + 30)) tail -s 0.05 --pid="$camera" -f /dev/null; done
  sleep 0.5
  kill -INT "$estimator" "$probe" ${recorder:+"$recorder"} 2>/dev/null
  timeout $((seconds + 30)) tail -s 0.05 --pid="$estimator" -f /dev/null
  wait "$estimator"
  local rc=$?
  timeout 30 tail -s 0.05 --pid="$probe" -f /dev/null
  [ -z "$recorder" ] || timeout 30 tail -s 0.05 --pid="$recorder" -f /dev/null
  [ "$rc" -eq 0 ] && pass "$name: estimator exited cleanly" || { fail "$name: estimator exit $rc"; tail "$work/$name.log"; }
}

probe_args=()  # extra panoptes_ros2_probe arguments of the next run_live
record_topics=()  # topics panoptes_record records during the next run_live ("all": its defaults); none: no recorder

# recorded_ros2 MCAP PROBE_JSONL TOPIC...: the recording's ROS 2 channels decode with Foxglove's own
# decoders (@foxglove/ros2idl-parser, @foxglove/rosmsg2-serialization, @mcap/core) as their ROS 2
# types, and their messages are the ones the probe received (frame numbers or stamps), issue 34 item 7.
recorded_ros2() {
  local mcap="$1" probe="$2"
  shift 2
  if [ ! -d "$source_dir/tests/mcap/node_modules/@mcap/core" ]; then
    [ -n "${CI:-}" ] && fail "tests/mcap/node_modules missing (deploy/install-deps.sh runs npm ci)" ||
      echo "SKIP: recorded ROS 2 topics: tests/mcap/node_modules missing (run npm ci in tests/mcap)"
    return
  fi
  rm -rf "$mcap.dump"
  node "$source_dir/tests/mcap/decode_ros2.mjs" "$mcap" --dump-dir "$mcap.dump" >"$mcap.json" 2>&1
  python3 "$source_dir/tests/tools/check_recorded_ros2.py" "$mcap.json" "$mcap.dump" "$probe" "$@" &&
    pass "recorded ROS 2 topics decode with Foxglove's decoders as their ROS 2 types: $*" ||
    fail "recorded ROS 2 topics (see above; $mcap.json)"
}

# tf_rate FILE LIMIT WHAT: /tf messages per second of header stamps (reliable reader) within 5 % of LIMIT.
tf_rate() {
  python3 - "$1" "$2" <<'EOF' && pass "$3: /tf at its limit of $2 Hz +-5 %" || fail "$3: /tf rate (limit $2 Hz)"
import json, sys
limit = float(sys.argv[2])
stamps = sorted(s["transforms"][0]["header"]["sec"] * 1_000_000_000 + s["transforms"][0]["header"]["nanosec"]
                for line in open(sys.argv[1]) for s in [json.loads(line)] if s["topic"] == "rt/tf" and s["qos"] == "reliable")
rate = (len(stamps) - 1) / ((stamps[-1] - stamps[0]) * 1e-9) if len(stamps) > 1 else 0.0
gaps = [(b - a) * 1e-6 for a, b in zip(stamps, stamps[1:])]
print(f"/tf: {len(stamps)} messages, {rate:.2f} per second of stamps (limit {limit:g}); "
      f"intervals min {min(gaps, default=0):.3f} max {max(gaps, default=0):.3f} ms")
sys.exit(0 if abs(rate - limit) <= 0.05 * limit else 1)
EOF
}

# --- default settings, per-camera frames ---------------------------------------------------------------------------
record_topics=(all)
run_live default 8 --frames per-camera  # the per-camera stream: ROS 2 poses compared with --out-poses
record_topics=()
recorded_ros2 "$work/default.mcap" "$work/default.ros2.jsonl" /tf /rigid_bodies /markers
tf_rate "$work/default.ros2.jsonl" 120 "per-camera frames, default ros2.tf_rate_hz"
grep -q "ROS 2: body" "$work/default.log" && fail "valid body names were renamed" || pass "head and tool keep their names"
python3 - "$work/default.ros2.jsonl" "$work/default.poses.jsonl" "$work/ros2_poses.jsonl" <<'EOF' &&
import collections, json, sys
ros2_file, poses_file, out_file = sys.argv[1:4]
failures = []
def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what)
    if not ok: failures.append(what)
def ns(header): return header["sec"] * 1_000_000_000 + header["nanosec"]

# A stamp can carry two poses (a fresh clone's run wrote 2 of 7216 so): two frames processed at the
# same stamp are published each; a sample matches either, compared at its own stamp as before.
own = collections.defaultdict(list)
for line in open(poses_file):
    pose = json.loads(line)
    own[(pose["body"], pose["stamp_ns"])].append(pose)
samples = collections.defaultdict(list)
for line in open(ros2_file):
    sample = json.loads(line)
    samples[(sample["topic"], sample["qos"])].append(sample)
topics = ["rt/tf", "rt/rigid_bodies", "rt/markers"] + [f"rt/panoptes/{b}/{k}" for b in ("head", "tool") for k in ("pose", "twist")]
frames = len(samples[("rt/rigid_bodies", "reliable")])
print(f"rt/rigid_bodies frames received reliably: {frames}; own poses: {len(own)}")
check(frames > 2000, "thousands of frames on rt/rigid_bodies")
for topic in topics:
    for qos in ("best_effort", "reliable"):
        n = len(samples[(topic, qos)])
        least = 500 if topic == "rt/tf" else 1000  # /tf: 120 a second by default (ros2.tf_rate_hz)
        # rt/tf is reliable (ROS 2's /tf): what the transport drops on the way to the probe, its
        # reliable reader gets again and its best-effort reader does not. On a starved two-core
        # machine that reader had 87.8 % (CI, stop 72), 91.3 % and 78.7 % (loaded runs, stop 73)
        # of the reliable one's; idle 100 %. The bound catches a reader that gets none or a
        # fraction, not what a best-effort reader may lose. The others are best-effort topics
        # that offer reliability: both readers lose alike, and the best-effort one keeps 95 %.
        share = 0.7 if topic == "rt/tf" else 0.95
        check(n >= share * len(samples[(topic, "reliable")]) and n > least,
              f"{topic} {qos}: {n} samples (reliable reader: {len(samples[(topic, 'reliable')])})")

# Poses: the estimator's own Pose JSONL, bit for bit, stamped with its capture stamp.
matched = total = 0
with open(out_file, "w") as out:
    for body in ("head", "tool"):
        for sample in samples[(f"rt/panoptes/{body}/pose", "reliable")]:
            total += 1
            matched += any(pose["p"] == sample["p"] and pose["q"] == sample["q"]
                           for pose in own.get((body, ns(sample["header"])), []))
            out.write(json.dumps({"stamp_ns": ns(sample["header"]), "body": body, "p": sample["p"], "q": sample["q"]}) + "\n")
check(total > 0 and matched == total, f"pose samples equal the estimator's poses at their stamps: {matched}/{total}")
twists = samples[("rt/panoptes/head/twist", "reliable")]
check(all(any(pose["v"] == t["v"] and pose["w"] == t["w"] for pose in own.get(("head", ns(t["header"])), []))
          for t in twists), "twists carry the poses' velocities")

every_header = [s["header"] for topic in topics for s in samples[(topic, "reliable")] if "header" in s]
every_header += [t["header"] for s in samples[("rt/tf", "reliable")] for t in s["transforms"]]
check(all(h["frame_id"] == "world" for h in every_header), "every header.frame_id is 'world'")
check(all(0 <= h["nanosec"] < 1_000_000_000 for h in every_header), "nanosec in [0, 1e9)")
children = {t["child_frame_id"] for s in samples[("rt/tf", "reliable")] for t in s["transforms"]}
check(children == {"head", "tool"}, f"tf child frames {sorted(children)}")

# RigidBodies and Markers: frame numbers rise; labelled markers by name and index, loose ones by index.
for topic in ("rt/rigid_bodies", "rt/markers"):
    numbers = [s["frame_number"] for s in samples[(topic, "reliable")]]
    check(numbers == sorted(numbers) and len(set(numbers)) == len(numbers) and numbers[0] >= 1, f"{topic} frame numbers rise")
bodies_markers = [(b["name"], m) for s in samples[("rt/rigid_bodies", "reliable")] for b in s["rigidbodies"] for m in b["markers"]]
check(len(bodies_markers) > 0 and all(m["id_type"] == 2 and m["name"] == f"{name}/{m['index']}" for name, m in bodies_markers),
      "rigid bodies carry their labelled markers as '<body>/<index>', USE_BOTH")
markers = [m for s in samples[("rt/markers", "reliable")] for m in s["markers"]]
labelled = [m for m in markers if m["id_type"] == 2]
loose = [m for m in markers if m["id_type"] == 1]
check(len(labelled) > 0 and len(loose) > 0 and len(labelled) + len(loose) == len(markers), f"markers: {len(labelled)} labelled, {len(loose)} unlabelled")
check(all(m["name"] == "" and m["index"] > 0 for m in loose), "unlabelled markers by track id")
sys.exit(1 if failures else 0)
EOF
  pass "ROS 2 samples checked" || fail "ROS 2 samples (see above)"
expect_exit 0 "poses read from the ROS 2 topics agree with the truth (<= 2 mm, no wrong poses)" -- \
  "$bin/panoptes_eval" --scene "$scene" --poses "$work/ros2_poses.jsonl" --epoch-ns "$epoch" --warmup 1 \
  --require-pose-rmse-mm 2 --require-no-wrong-poses
cat "$work/last.out"

# --- fixed-rate frames, a tf limit and a namespace -------------------------------------------------
# (One run for these and the ros2: keys of a configuration file, to keep the test short: issue 31.)
printf 'ros2:\n  frame_id: map\n  child_frame_prefix: "mocap/"\n' >"$work/ros2.yaml"
probe_args=(--namespace /lab1 /)
record_topics=(rt/lab1/rigid_bodies rt/lab1/markers rt/lab1/panoptes/head/pose rt/lab1/panoptes/tool/twist)
run_live namespaced 8 --frames fixed --frame-rate-hz 240 --ros2-tf-rate-hz 100 --ros2-namespace /lab1 --config "$work/ros2.yaml"
record_topics=()
recorded_ros2 "$work/namespaced.mcap" "$work/namespaced.ros2.jsonl" /lab1/rigid_bodies /lab1/markers \
  /lab1/panoptes/head/pose /lab1/panoptes/tool/twist
probe_args=()
tf_rate "$work/namespaced.ros2.jsonl" 100 "fixed 240 Hz frames, --ros2-tf-rate-hz 100"
python3 - "$work/namespaced.ros2.jsonl" <<'EOF' && pass "--ros2-namespace /lab1: every ROS 2 topic but /tf under /lab1, none bare" ||
import collections, json, sys
count = collections.Counter(s["topic"] for line in open(sys.argv[1]) for s in [json.loads(line)] if s["qos"] == "reliable")
print(dict(count))
namespaced = ["rt/lab1/rigid_bodies", "rt/lab1/markers"] + [f"rt/lab1/panoptes/{b}/{k}" for b in ("head", "tool") for k in ("pose", "twist")]
bare = [t.replace("rt/lab1/", "rt/") for t in namespaced]
sys.exit(0 if all(count[t] > 100 for t in namespaced) and count["rt/tf"] > 100 and all(count[t] == 0 for t in bare) else 1)
EOF
  fail "--ros2-namespace: topics (see above)"

# --- the ros2: keys, and --no-ros2 ---------------------------------------------------------------
python3 - "$work/namespaced.ros2.jsonl" <<'EOF' && pass "frame_id and child_frame_prefix from the configuration" || fail "configured frame ids"
import json, sys
tf = [t for line in open(sys.argv[1]) for s in [json.loads(line)] if s["topic"] == "rt/tf" for t in s["transforms"]]
poses = [s for line in open(sys.argv[1]) for s in [json.loads(line)] if s["topic"].endswith("/pose")]
print(len(tf), "transforms,", len(poses), "poses")
sys.exit(0 if tf and poses and all(t["header"]["frame_id"] == "map" and t["child_frame_id"] in ("mocap/head", "mocap/tool") for t in tf)
         and all(p["header"]["frame_id"] == "map" for p in poses) else 1)
EOF
run_live disabled 3 --config "$work/ros2.yaml" --no-ros2
[ -s "$work/disabled.poses.jsonl" ] && [ ! -s "$work/disabled.ros2.jsonl" ] && pass "--no-ros2: poses, but no ROS 2 topics" ||
  fail "--no-ros2 still published ROS 2 topics (or no poses at all)"
expect_exit 0 "--print-config shows the ros2 keys" -- "$bin/estimator_node" --config "$work/ros2.yaml" --no-ros2 --print-config
grep -q 'enabled: false' "$work/last.out" && grep -q 'frame_id: "map"' "$work/last.out" &&
  grep -q 'child_frame_prefix: "mocap/"' "$work/last.out" && pass "printed ros2 keys" || fail "printed ros2 keys"
printf 'ros2:\n  frame_id: /world\n' >"$work/bad.yaml"
expect_exit 2 "a bad ros2.frame_id is refused" -- "$bin/estimator_node" --config "$work/bad.yaml" --print-config
expect_stderr_contains "ros2.frame_id" "the error names the key"
expect_exit 2 "a bad --ros2-namespace is refused" -- "$bin/estimator_node" --ros2-namespace /lab1/ --print-config
expect_stderr_contains "--ros2-namespace" "the error names the option"
finish
