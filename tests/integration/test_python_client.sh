#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The Python package `panoptes` live (issue 15 items 2 and 5, docs/clients.md "Python"): the clients
# scene (two bodies, two loose markers, six asynchronous cameras) through estimator_node, read by
# tests/tools/python_client_probe.py (a panoptes.Client). The Python client receives >= 99% of the
# published frames over 20 s, its poses equal the estimator's own --out-poses bit for bit (float.hex),
# body names and descriptions are right; the estimator is killed (-9) and restarted and delivery
# resumes within 2 s without restarting the client. The examples run headless: log_poses_csv.py
# writes the estimator's poses to CSV exactly, plot_body.py a PNG; on an empty domain the client
# returns None within the timeout and log_poses_csv.py exits 1 saying so. `cmake --install` gives a
# package that imports from <prefix>/lib/python3/dist-packages and finds the installed library and profile.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/clients.yaml"
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-0}"
python=$(cat "$build_dir/python/INTERPRETER" 2>/dev/null)
[ -n "$python" ] && [ -f "$build_dir/python/panoptes/__init__.py" ] || { fail "the Python package is not built ($build_dir/python)"; finish; }
export PYTHONPATH="$build_dir/python"
for tool in estimator_node camera_node panoptes_sim; do
  [ -x "$bin/$tool" ] || { fail "$bin/$tool is not built"; finish; }
done

# --- an empty domain ----------------------------------------------------------------------------
empty_domain=$(( (PANOPTES_DOMAIN + 117) % 233 ))
expect_exit 0 "wait_for_frame on an empty domain returns None within the timeout" -- "$python" -c "
import re, time, panoptes
with panoptes.Client(domain=$empty_domain) as c:
    start = time.monotonic()
    frame = c.wait_for_frame(1.0)
    elapsed = time.monotonic() - start
    print(c.status_text())
    assert frame is None and 0.99 <= elapsed < 2.0, (frame, elapsed)
    assert re.search(r'no data for [0-9]+[.][0-9] s', c.status_text()), c.status_text()"
start=$(date +%s%N)
expect_exit 1 "log_poses_csv.py on an empty domain exits non-zero" -- "$python" "$source_dir/examples/log_poses_csv.py" \
  --domain "$empty_domain" --timeout 2 --out "$work/empty.csv"
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
expect_stderr_matches "no data for [0-9]+\\.[0-9] s" "it says 'no data for N s'"
expect_stderr_contains "is estimator_node running?" "it says what to check"
[ "$elapsed_ms" -lt 6000 ] && pass "it gave up within the timeout ($elapsed_ms ms for --timeout 2, interpreter start included)" ||
  fail "it took $elapsed_ms ms for --timeout 2"
expect_exit 2 "log_poses_csv.py rejects a bad argument" -- "$python" "$source_dir/examples/log_poses_csv.py" --duration soon
expect_stderr_contains "--duration" "the error names the argument"
expect_exit 1 "plot_body.py on an empty domain exits non-zero" -- "$python" "$source_dir/examples/plot_body.py" \
  --domain "$empty_domain" --timeout 1 --duration 2 --save "$work/empty.png"
expect_stderr_matches "no data for [0-9]+\\.[0-9] s" "it says 'no data for N s'"

# --- installed: cmake --install puts the package in <prefix>/lib/python3/dist-packages --------------
prefix="$work/prefix"
expect_exit 0 "cmake --install into a prefix" -- cmake --install "$build_dir" --prefix "$prefix"
expect_exit 0 "the installed package imports and finds libpanoptes_client.so and the installed profile" -- \
  env -u PANOPTES_DDS_PROFILE PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" -c "
import panoptes, sys
assert panoptes.__file__.startswith('$prefix/lib/python3/dist-packages/panoptes/'), panoptes.__file__
with panoptes.Client(domain=$empty_domain) as c:
    assert c.profile_file == '$prefix/share/panoptes/dds/loopback.xml', c.profile_file
    assert c.wait_for_frame(0.2) is None"
# ldd's whole output first: grep -q would close the pipe early (SIGPIPE under pipefail).
libraries=$(ldd "$prefix"/lib/python3/dist-packages/panoptes/_panoptes*.so)
grep -q "libpanoptes_client.so.* => $prefix/lib/python3/dist-packages/panoptes/\.\./\.\./\.\./libpanoptes_client" <<<"$libraries" &&
  pass "the installed module loads the installed libpanoptes_client.so (RUNPATH \$ORIGIN)" ||
  { fail "the installed module does not find the installed library"; echo "$libraries"; }
rm -rf "$prefix"

# --- live: estimator, six cameras, the Python client; the estimator killed and restarted ------------
expect_exit 0 "simulate the clients scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
"$python" "$source_dir/tests/tools/python_client_probe.py" --out "$work/client.jsonl" --duration 32 >"$work/probe.log" 2>&1 &
probe=$!
pids+=("$probe")
replay_clients_scene_with_restart
sleep 3
"$python" "$source_dir/examples/plot_body.py" --body tool --duration 3 --save "$work/tool.png" >"$work/plot.out" 2>"$work/plot.err" &
plot=$!
pids+=("$plot")
expect_exit 0 "log_poses_csv.py logs live poses" -- "$python" "$source_dir/examples/log_poses_csv.py" --duration 3 \
  --out "$work/poses.csv"
wait "$plot" && [ -s "$work/tool.png" ] && grep -q "positions of 'tool' plotted" "$work/plot.err" &&
  pass "plot_body.py --save wrote a PNG ($(stat -c %s "$work/tool.png") bytes): $(cat "$work/plot.err")" ||
  { fail "plot_body.py"; cat "$work/plot.err"; }
"$python" -c "import sys, matplotlib.image as i; a = i.imread(sys.argv[1]); sys.exit(0 if a.shape[0] > 100 and a.std() > 0 else 1)" \
  "$work/tool.png" 2>/dev/null && pass "the PNG is an image with content" || fail "the PNG is not a plot"
timeout 30 tail --pid="$estimator" -f /dev/null
wait "$estimator"
rc=$?
[ "$rc" -eq 0 ] && pass "the restarted estimator exited cleanly" || { fail "estimator exit $rc"; tail -5 "$work/estimator2.log"; }
timeout 30 tail --pid="$probe" -f /dev/null
wait "$probe" || fail "python_client_probe exit $?"
cat "$work/probe.log"
published2=$(frames_published "$work/estimator2.log")

"$python" - "$work" "$restart_ns" "${published2:-0}" <<'PYTHON'
import csv, json, sys
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
check(len(runs) == 2, f"the Python client saw two estimator runs ({len(runs)})")
check(stats["estimator_restarts"] == 1, f"Stats counts one estimator restart ({stats['estimator_restarts']})")
check(stats["frames_malformed"] == 0 and stats["frames_dropped"] == 0 and stats["callback_errors"] == 0,
      f"nothing malformed or dropped ({stats['frames_malformed']}, {stats['frames_dropped']})")
if len(runs) == 2:
    published = runs[0][-1]["frame"] + published2  # the killed run: up to its last frame the client saw
    received = len(runs[0]) + len(runs[1])
    span_s = (frames[-1]["receive_ns"] - frames[0]["receive_ns"]) * 1e-9
    check(published2 > 0 and runs[1][-1]["frame"] == published2,
          f"the client has the restarted estimator's last frame ({runs[1][-1]['frame']} of {published2})")
    first2 = runs[1][0]
    # Frames the new estimator wrote before its writer matched this reader cannot reach any volatile
    # subscriber (discovery: tens of ms on an idle loopback, up to a second on a busy host); they are
    # left out here and bounded by the resume check below.
    before_match = first2["frame"] - 1
    matched = published - before_match
    check(span_s >= 20 and received >= 0.99 * matched,
          f"received {received} of {matched} frames published while matched ({100.0 * received / max(matched, 1):.2f}%) "
          f"over {span_s:.1f} s; {published} published in all, {before_match} by the new estimator before discovery")
    check(len(runs[0]) >= 0.99 * runs[0][-1]["frame"],
          f"first run: {len(runs[0])} of {runs[0][-1]['frame']} frames ({100.0 * len(runs[0]) / runs[0][-1]['frame']:.2f}%)")
    resume_s = (first2["receive_ns"] - restart_ns) * 1e-9
    check(resume_s <= 2.0, f"delivery resumed {resume_s:.3f} s after the estimator was restarted "
          f"(first frame of the new run: {first2['frame']})")

# Poses bit for bit against the estimator's own output (matched by stamp and body).
estimator = {}
for run in (1, 2):
    for l in open(f"{work}/poses{run}.jsonl"):
        try:
            p = json.loads(l)
        except ValueError:
            continue  # the killed run's last line may be cut
        estimator[(p["stamp_ns"], p["body"])] = p
exact = lambda hexes, values: [float.fromhex(h) for h in hexes] == [float(v) for v in values]
compared = equal = 0
names = set()
for f in frames:
    for b in f["bodies"]:
        names.add(b["name"])
        p = estimator.get((f["stamp_ns"], b["name"])) if b["valid"] else None
        if p is None:
            continue
        compared += 1
        if (exact(b["p"], p["p"]) and exact(b["q"], p["q"]) and exact(b["v"], p["v"]) and exact(b["w"], p["w"])
                and exact(b["sigma"], p["sigma"]) and b["horizon_ns"] == p["horizon_ns"]):
            equal += 1
        elif compared - equal <= 3:
            print("  differs:", f["stamp_ns"], b, p)
valid = sum(1 for f in frames for b in f["bodies"] if b["valid"])
check(compared >= 0.95 * valid and compared > 5000,
      f"{compared} of the Python client's {valid} tracked poses found in the estimator's --out-poses")
check(compared > 0 and equal == compared, f"{equal} of {compared} poses equal bit for bit (position, quaternion, velocities, sigma)")
check(names == {"head", "tool"}, f"body names in frames: {sorted(names)}")
check(all(f["unlabelled"] + f["labelled"] == f["markers"] for f in frames) and
      sum(f["unlabelled"] > 0 for f in frames) > 0.9 * len(frames) and sum(f["labelled"] > 0 for f in frames) > 0.9 * len(frames),
      "frames carry labelled and unlabelled markers")

# The simulator's bodies.yaml, read without PyYAML (not a dependency): `- name: "x"` and `- [x, y, z]`.
defined = []
for line in open(f"{work}/sim/bodies.yaml"):
    item = line.strip()
    if item.startswith("- name:"):
        defined.append({"name": item.split(":", 1)[1].strip().strip('"'), "markers": []})
    elif item.startswith("- [") and defined:
        defined[-1]["markers"].append(json.loads(item[2:]))
check(len(defined) == 2 and all(len(b["markers"]) >= 4 for b in defined), f"bodies.yaml read: {defined}")
descriptions = [l for l in lines if l["type"] == "descriptions"]
check(len(descriptions) >= 1 and stats["descriptions_received"] >= 2,
      f"descriptions received {stats['descriptions_received']} times (once per estimator run)")
last = descriptions[-1]["bodies"] if descriptions else []
check([d["name"] for d in last] == [b["name"] for b in defined] and [d["id"] for d in last] == [1, 2],
      f"description names and ids: {[(d['name'], d['id']) for d in last]}")
check(all(d["markers"] == [[float(x) for x in m] for m in b["markers"]] and d["kind"] == "passive"
          for d, b in zip(last, defined)), "description marker layouts equal the bodies file")

# log_poses_csv.py: the header, two bodies per frame, values equal to the estimator's poses.
rows = list(csv.DictReader(open(f"{work}/poses.csv")))
check(len(rows) > 1000 and {r["body"] for r in rows} == {"head", "tool"}, f"the CSV has {len(rows)} rows of head and tool")
matched = [(r, estimator.get((int(r["stamp_ns"]), r["body"]))) for r in rows if r["valid"] == "1"]
matched = [(r, p) for r, p in matched if p is not None]
same = sum(1 for r, p in matched if [float(r[k]) for k in ("x", "y", "z")] == p["p"]
           and [float(r[k]) for k in ("qx", "qy", "qz", "qw")] == p["q"])
check(len(matched) > 0.95 * len(rows) and same == len(matched),
      f"{same} of {len(matched)} CSV poses (of {len(rows)} rows) equal the estimator's exactly")
sys.exit(1 if failures else 0)
PYTHON
[ $? -eq 0 ] || failures=$((failures + 1))
finish
