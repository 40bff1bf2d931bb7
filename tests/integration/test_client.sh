#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The C++ client library live (issue 15, docs/clients.md): the clients scene (two bodies, two loose
# markers, six asynchronous cameras) through estimator_node, read by panoptes_client_probe (an
# application on libpanoptes_client) and by examples/sample_client. The client receives >= 99% of
# the published frames, its poses equal the estimator's own --out-poses bit for bit, body names and
# descriptions are right; the estimator is killed (-9) and restarted mid-run and delivery resumes
# within 2 s without restarting the client; a client on an empty domain says so and exits non-zero.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/clients.yaml"
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-0}"
for tool in panoptes_client_probe sample_client estimator_node camera_node panoptes_sim; do
  [ -x "$bin/$tool" ] || { fail "$bin/$tool is not built"; finish; }
done

# --- a client on an empty domain ----------------------------------------------------------------
empty_domain=$(( (PANOPTES_DOMAIN + 117) % 233 ))
start=$(date +%s%N)
expect_exit 1 "sample_client on an empty domain exits non-zero" -- "$bin/sample_client" --domain "$empty_domain" --timeout-s 2
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
expect_stderr_matches "no data for [0-9]+\\.[0-9] s" "it reports 'no data for N s'"
[ "$elapsed_ms" -lt 5000 ] && pass "it gave up within the timeout ($elapsed_ms ms for --timeout-s 2)" ||
  fail "it took $elapsed_ms ms for --timeout-s 2"
expect_exit 2 "sample_client rejects a bad argument" -- "$bin/sample_client" --frames many
expect_stderr_contains "--frames many" "the error names the argument"

# --- live: estimator, six cameras, the client; the estimator killed and restarted -----------------
expect_exit 0 "simulate the clients scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
"$bin/panoptes_client_probe" --out "$work/client.jsonl" --duration 32 >"$work/probe.log" 2>&1 &
probe=$!
pids+=("$probe")
replay_clients_scene_with_restart
sleep 4
# PTZ guidance on the same live frames (docs/ptz.md): ptz_guide follows the body "head".
"$bin/ptz_guide" --ptz "$source_dir/deploy/ptz/walk_side.yaml" --body head --duration 3 --out "$work/ptz.jsonl" \
  >"$work/ptz.log" 2>&1 &
ptz_guide=$!
pids+=("$ptz_guide")
expect_exit 0 "sample_client prints live frames" -- "$bin/sample_client" --frames 300 --timeout-s 5
grep -q "body 1 head .*tracked" "$work/last.out" && grep -q "body 2 tool" "$work/last.out" &&
  grep -q "marker .* unlabelled" "$work/last.out" && grep -q "marker .* head\[" "$work/last.out" &&
  pass "it prints bodies and labelled and unlabelled markers" || { fail "sample_client output"; head -20 "$work/last.out"; }
timeout 10 tail --pid="$ptz_guide" -f /dev/null
python3 - "$work/ptz.jsonl" <<'PY' && pass "ptz_guide steered at the live body 'head' ($(wc -l <"$work/ptz.jsonl") commands)" ||
import json, math, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
stamps = [c["issued_ns"] for c in lines]
ok = len(lines) >= 45 and stamps == sorted(stamps) and all(math.isfinite(c[k]) for c in lines for k in c)
ok = ok and max(c["pan"] for c in lines) - min(c["pan"] for c in lines) > 1e-4  # it follows a moving head
sys.exit(0 if ok else 1)
PY
  { fail "ptz_guide live commands"; tail -3 "$work/ptz.log"; head -3 "$work/ptz.jsonl"; }
timeout 30 tail --pid="$estimator" -f /dev/null
wait "$estimator"
rc=$?
[ "$rc" -eq 0 ] && pass "the restarted estimator exited cleanly" || { fail "estimator exit $rc"; tail -5 "$work/estimator2.log"; }
timeout 30 tail --pid="$probe" -f /dev/null
wait "$probe" || fail "panoptes_client_probe exit $?"
cat "$work/probe.log"
published2=$(frames_published "$work/estimator2.log")

python3 - "$work" "$restart_ns" "${published2:-0}" <<'PYTHON'
import json, sys, yaml
work, restart_ns, published2 = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
failures = 0
def check(ok, what):
    global failures
    print(("PASS: " if ok else "FAIL: ") + what)
    failures += 0 if ok else 1

lines = [json.loads(l) for l in open(f"{work}/client.jsonl")]
frames = [l for l in lines if l["type"] == "frame"]
stats = [l for l in lines if l["type"] == "stats"][-1]
runs = [[]]
for f in frames:
    if runs[-1] and f["frame"] <= runs[-1][-1]["frame"]:
        runs.append([])
    runs[-1].append(f)
check(len(runs) == 2, f"the client saw two estimator runs ({len(runs)})")
check(stats["estimator_restarts"] == 1, f"Stats counts one estimator restart ({stats['estimator_restarts']})")
check(stats["frames_malformed"] == 0 and stats["descriptions_malformed"] == 0, "nothing malformed")
if len(runs) == 2:
    # Run 1 was killed: what it published is known up to its last frame number the client saw.
    # Frames the new estimator wrote before its writer matched this reader cannot be delivered to
    # anyone (rt/panoptes/frames is volatile); discovery usually takes tens of milliseconds on
    # loopback but up to a second on a loaded machine. So the share is over the frames published
    # while matched, and the gap is bounded by the resume check below (as test_python_client).
    first2 = runs[1][0]
    published1 = runs[0][-1]["frame"] - runs[0][0]["frame"] + 1
    published = published1 + published2 - first2["frame"] + 1
    received = len(runs[0]) + len(runs[1])
    span_s = (frames[-1]["receive_ns"] - frames[0]["receive_ns"]) * 1e-9
    check(published2 > 0 and runs[1][-1]["frame"] == published2,
          f"the client has the restarted estimator's last frame ({runs[1][-1]['frame']} of {published2})")
    check(span_s >= 20 and received >= 0.99 * published,
          f"received {received} of {published} frames published while matched "
          f"({100.0 * received / max(published, 1):.2f}%) over {span_s:.1f} s")
    resume_s = (first2["receive_ns"] - restart_ns) * 1e-9
    gap_s = (first2["receive_ns"] - runs[0][-1]["receive_ns"]) * 1e-9
    check(resume_s <= 2.0, f"delivery resumed {resume_s:.3f} s after the estimator was restarted "
          f"(first frame of the new run: {first2['frame']}; {gap_s:.3f} s since the killed run's last frame)")

# Poses bit for bit against the estimator's own output (matched by stamp and body).
estimator = {}
for run in (1, 2):
    for l in open(f"{work}/poses{run}.jsonl"):
        try:
            p = json.loads(l)
        except ValueError:
            continue  # the killed run's last line may be cut
        estimator[(p["stamp_ns"], p["body"])] = p
compared = equal = 0
names = set()
for f in frames:
    for b in f["bodies"]:
        names.add(b["name"])
        if not b["valid"]:
            continue
        p = estimator.get((f["stamp_ns"], b["name"]))
        if p is None:
            continue
        compared += 1
        if (b["p"] == p["p"] and b["q"] == p["q"] and b["v"] == p["v"] and b["w"] == p["w"]
                and b["sigma"] == p["sigma"] and b["horizon_ns"] == p["horizon_ns"]):
            equal += 1
        elif compared - equal <= 3:
            print("  differs:", f["stamp_ns"], b, p)
valid = sum(1 for f in frames for b in f["bodies"] if b["valid"])
check(compared >= 0.95 * valid and compared > 5000,
      f"{compared} of the client's {valid} tracked poses found in the estimator's --out-poses")
check(compared > 0 and equal == compared, f"{equal} of {compared} poses equal bit for bit (position, quaternion, velocities, sigma)")
check(names == {"head", "tool"}, f"body names in frames: {sorted(names)}")

# Body descriptions: those of the bodies file, known again after the restart.
defined = yaml.safe_load(open(f"{work}/sim/bodies.yaml"))["bodies"]
descriptions = [l for l in lines if l["type"] == "descriptions"]
check(len(descriptions) >= 1 and stats["descriptions_received"] >= 2,
      f"descriptions received {stats['descriptions_received']} times (once per estimator run)")
last = descriptions[-1]["bodies"] if descriptions else []
check([d["name"] for d in last] == [b["name"] for b in defined] and [d["id"] for d in last] == [1, 2],
      f"description names and ids: {[(d['name'], d['id']) for d in last]}")
check(all(d["markers"] == [[float(x) for x in m] for m in b["markers"]] and d["kind"] == "passive"
          for d, b in zip(last, defined)), "description marker layouts equal the bodies file")
sys.exit(1 if failures else 0)
PYTHON
[ $? -eq 0 ] || failures=$((failures + 1))
finish
