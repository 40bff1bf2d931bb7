# SPDX-License-Identifier: Apache-2.0
# Shared helpers for the integration tests: bounded waits, assertions, cleanup on every exit.
set -uo pipefail
build_dir="$1"
source_dir="$2"
bin="$build_dir/bin"
work="$(mktemp -d /tmp/panoptes-test-XXXXXX)"
export PANOPTES_DDS_PROFILE="$source_dir/deploy/dds/loopback.xml"
# The test's DDS domain (docs/testing.md, "DDS domains"): ctest gives each integration test one of
# its own (PANOPTES_DOMAIN) and a second that nobody publishes on (PANOPTES_EMPTY_DOMAIN), so that
# tests run in parallel without seeing each other. Run by hand: 0 and (domain + 117) % 233.
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-0}"
empty_domain="${PANOPTES_EMPTY_DOMAIN:-$(( (PANOPTES_DOMAIN + 117) % 233 ))}"
pids=()
failures=0

# Up to 0.5 s for the processes still running to end on SIGINT (most tests waited for theirs
# already: the fixed 0.5 s it was cost every test that much), then KILL.
cleanup() {
  local alive pid
  for pid in "${pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
  for _ in 1 2 3 4 5; do
    alive=0
    for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && { alive=1; break; }; done
    [ "$alive" -eq 0 ] && break
    sleep 0.1
  done
  for pid in "${pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  bash "$source_dir/deploy/dds-shm-clean.sh"
  if [ "$failures" -eq 0 ] && [ -z "${PANOPTES_KEEP_WORK:-}" ]; then rm -rf "$work"; else echo "kept $work for inspection"; fi
}
trap cleanup EXIT

pass() { echo "PASS: $*"; }
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# expect_exit CODE DESCRIPTION -- command...   (stderr captured in $work/last.err)
expect_exit() {
  local code="$1" what="$2"
  shift 3
  "$@" >"$work/last.out" 2>"$work/last.err"
  local rc=$?
  if [ "$rc" -eq "$code" ]; then pass "$what (exit $rc)"; else fail "$what: exit $rc, expected $code"; cat "$work/last.err"; fi
}

# expect_stderr_contains TEXT DESCRIPTION
expect_stderr_contains() {
  if grep -qF -- "$1" "$work/last.err"; then pass "$2"; else fail "$2: stderr lacks '$1'"; cat "$work/last.err"; fi
}

# frames_published ESTIMATOR_LOG: how many frames produced output (a MocapFrame each): the frames the
# tracker processed less those replayed late, too late or from uncalibrated cameras (the summary line).
frames_published() {
  sed -n 's/.*processed \([0-9]*\) frames (\([0-9]*\) late and replayed, \([0-9]*\) too late, \([0-9]*\) from uncalibrated.*/\1 \2 \3 \4/p' "$1" |
    awk '{print $1 - $2 - $3 - $4}'
}

# expect_stderr_matches ERE DESCRIPTION: like expect_stderr_contains, for an extended regular expression.
expect_stderr_matches() {
  if grep -qE -- "$1" "$work/last.err"; then pass "$2"; else fail "$2: stderr does not match '$1'"; cat "$work/last.err"; fi
}

# require_shared_data PATH: data read from ../shared/data (not copied into tests/data) follows the
# rule of tests/data/README.md: missing, it fails the test under CI and skips it (exit 77) elsewhere.
# Checks that already failed are reported, never hidden by the skip.
require_shared_data() {
  [ -e "$1" ] && return 0
  if [ -n "${CI:-}" ] || [ "$failures" -ne 0 ]; then
    fail "$1 is missing (../shared/data must sit beside the checkout under CI; tests/data/README.md)"
    finish
  fi
  echo "SKIP: $1 is missing (../shared/data beside the checkout; tests/data/README.md)"
  exit 77
}

# walk1_in_walk8 OUT [SED_EXPRESSION...]: walk8.yaml's eight cameras and effects playing the Gait2392
# subject01 walk1 (../shared/data/static) instead of its 41-marker walk, 0.3 false blobs per frame,
# with further sed expressions (duration, seed, start) applied after; written to OUT.
walk1_in_walk8() {
  local out="$1" static_data="$source_dir/../shared/data/static"
  shift
  local extra=()
  for expression in "$@"; do extra+=(-e "$expression"); done
  sed -e 's/^  false_blobs: .*/  false_blobs: 0.3/' -e "s#^  file: .*#  file: $static_data/gait2392_subject01_walk1.trc#"     -e 's/^  offset: .*/  offset: [-0.58, 0, 0]/' "${extra[@]}" "$source_dir/deploy/scenes/walk8.yaml" >"$out"
}

# label_offline SIM_DIR MODELS LABELS [WHAT [ARGS...]]: estimator_node --subjects MODELS offline over
# the simulator's features in SIM_DIR (Torso soft), ARGS added, names written to LABELS; its labels
# line echoed.
label_offline() {
  expect_exit 0 "${4:-estimator_node --subjects offline}" -- "$bin/estimator_node" --calibration "$1/calibration.yaml" \
    --in-features "$1"/cam*.jsonl --no-dds --subjects "$2" --soft-segments Torso --out-labels "$3" "${@:5}"
  grep "labels:" "$work/last.err" || true
}

# Waits for background process PID (a child of this shell) at most SECONDS, then kills it: a
# process that hangs on its way out (seen once: a recorder after closing its file, in Fast DDS's
# teardown) fails the test instead of holding it until ctest's timeout. Returns PID's exit status,
# or 124 when it had to be killed (and says so).
wait_bounded() {  # PID SECONDS NAME (tail -s 0.05: it looks at PID every 50 ms, not every second)
  if ! timeout "$2" tail -s 0.05 --pid="$1" -f /dev/null; then
    echo "$3 (pid $1) still running after $2 s: killed"
    kill -KILL "$1" 2>/dev/null
    wait "$1" 2>/dev/null
    return 124
  fi
  wait "$1"
}

# expect_clean_exit PID NAME LOG: waits for background process PID (a child of this shell) and
# passes when it exited 0; otherwise the failure names the exit status (128 + N: killed by signal N)
# and the last lines of LOG in one line (CI's failure digest shows only FAIL lines), then the log's tail.
# Callers wait for PID first (bounded); one still running 10 s later gets SIGABRT, whose crash report
# puts its call stack in LOG, and fails (a hung process fails the check, not the test's time limit).
expect_clean_exit() {
  local rc=0
  if ! timeout 10 tail -s 0.05 --pid="$1" -f /dev/null; then
    fail "$2 has not exited: SIGABRT for its call stack (in $3)"
    kill -ABRT "$1" 2>/dev/null
    timeout 10 tail -s 0.05 --pid="$1" -f /dev/null || kill -KILL "$1" 2>/dev/null
    wait "$1" 2>/dev/null
    tail -n 60 "$3" 2>/dev/null
    return 1
  fi
  wait "$1" || rc=$?
  # Its teardown stalled and its watchdog ended it (end_within, docs/architecture.md): not a failure
  # (the run's outputs were complete), but the log keeps where it stalled.
  if grep -q "after the work ended; ending now" "$3" 2>/dev/null; then
    echo "NOTE: $2 stalled in its teardown and its watchdog ended it:"
    grep -A 40 "after the work ended; ending now" "$3"
  fi
  if [ "$rc" -eq 0 ]; then pass "$2 exited cleanly"; return 0; fi
  fail "$2: exit $rc; last lines of its log: $(tail -n 3 "$3" 2>/dev/null | tr '\n' '|')"
  tail -n 20 "$3" 2>/dev/null
  return 1
}

finish() {
  if [ "$failures" -eq 0 ]; then echo "all checks passed"; exit 0; fi
  echo "$failures check(s) failed"
  exit 1
}

# start_console NAME [ARG...]: panoptes_console (with ARGs) on a free loopback port with a new token in
# $work/token (log $work/console.log, pid added); sets $url (with the token) and $port, or fails and finishes.
start_console() {
  printf '%s-test-%s\n' "$1" "$(head -c 12 /dev/urandom | od -An -tx1 | tr -d ' \n')" >"$work/token"
  shift
  "$bin/panoptes_console" --bind 127.0.0.1:0 --token-file "$work/token" --url-file "$work/url" "$@" >"$work/console.log" 2>&1 &
  pids+=("$!")
  for _ in $(seq 50); do [ -s "$work/url" ] && break; sleep 0.1; done
  url="$(cat "$work/url" 2>/dev/null)"
  [ -n "$url" ] && pass "console serving at ${url%%\?*}" || { fail "console did not start: $(cat "$work/console.log")"; finish; }
  port="${url#http://127.0.0.1:}"
  port="${port%%/*}"
}

# replay_cameras EPOCH_NS SECONDS CAMERA...: one camera_node per CAMERA replaying
# $work/sim/CAMERA.jsonl in real time from EPOCH_NS for SECONDS, logs in $work/CAMERA.log (pids added).
replay_cameras() {
  local epoch_ns=$1 seconds=$2 camera
  shift 2
  for camera in "$@"; do
    "$bin/camera_node" --source "features:$work/sim/$camera.jsonl" --sim-epoch-ns "$epoch_ns" --duration "$seconds" \
      --quiet >"$work/$camera.log" 2>&1 &
    pids+=("$!")
  done
}

# replay_clients_scene_with_restart: the client tests' live run (test_client.sh,
# test_python_client.sh). The simulated clients scene in $work/sim replayed by six camera_nodes
# (16 s) into estimator_node (run 1, --out-poses $work/poses1.jsonl), which is killed (-9) after
# 8 s and started again 1 s later (run 2, 9 s, $work/poses2.jsonl). Sets $restart_ns (when run 2
# started) and $estimator (its pid). Start the client under test first.
replay_clients_scene_with_restart() {
  local epoch=$(( ($(date +%s) + 3) * 1000000000 ))
  start_clients_estimator 1 30
  replay_cameras "$epoch" 16 c0 c1 c2 c3 c4 c5
  sleep 8
  kill -KILL "$estimator"
  wait "$estimator" 2>/dev/null
  sleep 1
  restart_ns=$(date +%s%N)
  start_clients_estimator 2 9  # until 2 s after the cameras (3 s until issue 31)
}
# The per-camera stream (--frames per-camera, not the live default): the client tests compare the
# client's poses with the estimator's --out-poses, which are one record set per camera frame.
start_clients_estimator() {  # RUN DURATION
  "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$work/sim/bodies.yaml" --frames per-camera \
    --out-poses "$work/poses$1.jsonl" --duration "$2" --status-period 1 >"$work/estimator$1.log" 2>&1 &
  estimator=$!
  pids+=("$estimator")
}

# require_browser: the console's browser tests need playwright-core (npm ci in the console's web
# folder) and Debian's chromium; skipped (77) without them outside CI, failed in CI. Sets $web.
require_browser() {
  web="$source_dir/tools/console/web"
  if [ ! -d "$web/node_modules/playwright-core" ] || [ ! -x /usr/bin/chromium ]; then
    if [ -n "${CI:-}" ]; then fail "playwright-core (npm ci in $web) or /usr/bin/chromium missing"; finish; fi
    echo "SKIP: playwright-core (npm ci in $web) or /usr/bin/chromium missing"; exit 77
  fi
}

# have_browser WHAT: for a test whose browser part is optional (WHAT names it): true with
# playwright-core and chromium; without them false, after a failure in CI or a SKIP line outside
# it. Sets $web.
have_browser() {
  web="$source_dir/tools/console/web"
  [ -d "$web/node_modules/playwright-core" ] && [ -x /usr/bin/chromium ] && return 0
  if [ -n "${CI:-}" ]; then
    fail "playwright-core (npm ci in $web) or /usr/bin/chromium missing"
  else
    echo "SKIP ($1): playwright-core or /usr/bin/chromium missing"
  fi
  return 1
}

# floor_recording NAME POINTS QUATERNIONS: the room ($work/room.yaml, a copy of
# deploy/scenes/wand_room.yaml) with the wand resting (1.5 s) and sliding (1 s)
# on the floor through the waypoints (each given twice: start and end of a rest), marker centres
# 7 mm up (their radius); features in $work/NAME/.
floor_recording() {
  local times="0, 1.5, 2.5, 4, 5, 6.5, 7, 8.5"
  sed -e '/^    path: {type: lissajous/d' -e '/^    rotation: {type: oscillate/d' "$work/room.yaml" >"$work/$1.yaml"
  printf '    path: {type: waypoints, points: [%s], times: [%s]}\n    rotation: {type: waypoints, q: [%s], times: [%s]}\n' \
    "$2" "$times" "$3" "$times" >>"$work/$1.yaml"
  expect_exit 0 "simulate the wand on the floor ($1)" -- "$bin/panoptes_sim" features --scene "$work/$1.yaml" \
    --out-dir "$work/$1" --duration 8.5
}
