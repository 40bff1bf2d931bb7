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
for tool in panoptes_client_probe sample_client estimator_node camera_node panoptes_sim; do
  [ -x "$bin/$tool" ] || { fail "$bin/$tool is not built"; finish; }
done

# --- a client on an empty domain ----------------------------------------------------------------
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
"$bin/panoptes_client_probe" --out "$work/client.jsonl" --duration 20 >"$work/probe.log" 2>&1 &
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
rate_line=$(grep -E "^sample_client: frames at [0-9]+\.[0-9]+ Hz \((fixed rate|one per processed camera frame)\)" "$work/last.err")
[ -n "$rate_line" ] && pass "it prints the frame rate the client measured: $rate_line" ||
  { fail "sample_client printed no frame rate"; cat "$work/last.err"; }
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

PYTHONPATH="$source_dir/tests/tools" python3 - "$work" "$restart_ns" "${published2:-0}" <<'PYTHON'
import sys
from client_run_check import (Checks, ClientRun, check_descriptions, check_poses_exact, check_restart_delivery,
                              read_estimator_poses)
work, restart_ns, published2 = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
checks = Checks("the client")
run = ClientRun(work)
checks.check(run.stats["frames_malformed"] == 0 and run.stats["descriptions_malformed"] == 0, "nothing malformed")
check_restart_delivery(checks, run, restart_ns, published2)
check_poses_exact(checks, run, read_estimator_poses(work), float)
check_descriptions(checks, run, f"{work}/sim/bodies.yaml")
sys.exit(1 if checks.failures else 0)
PYTHON
[ $? -eq 0 ] || failures=$((failures + 1))
finish
