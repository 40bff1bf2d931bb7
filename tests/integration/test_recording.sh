#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Issue 17, recording and replay (docs/recording.md), on a live simulated session (4 cameras x
# 120 Hz, three markers; panoptes_demo) recorded by four panoptes_record processes at once:
#   A records everything and stops on SIGINT: every published message is in the file (against the
#     camera nodes' and the estimator's own counters), @mcap/core reads it, and estimator_node
#     --in-recording gives tracks bit-identical to the offline JSONL path for the same features;
#   B is killed with SIGKILL mid-session: every message older than its last complete chunk is
#     recovered, by our reader and by @mcap/core;
#   C is driven by DDS commands (start, stop, quit);
#   D runs under a 300 KiB file size limit: it stops with a clear error and a valid file.
# Foxglove's own decoders (@foxglove/ros2idl-parser, @foxglove/rosmsg2-serialization) read every
# channel of A as its schema's type, and what they decode is what was published (issue 32).
# Then panoptes_replay publishes A's features into a live estimator (same tracks as the original
# run), and at --rate 10 says whether it kept up. Bad input: empty and foreign files.
source "$(dirname "$0")/lib.sh"
check_mcap() { node "$source_dir/tests/mcap/check_mcap.mjs" "$@"; }
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
if [ ! -d "$source_dir/tests/mcap/node_modules/@mcap/core" ] || [ ! -d "$source_dir/tests/mcap/node_modules/@foxglove/rosmsg2-serialization" ]; then
  if [ -n "${CI:-}" ]; then fail "tests/mcap/node_modules missing (deploy/install-deps.sh runs npm ci)"; finish; fi
  echo "SKIP: tests/mcap/node_modules missing (run npm ci in tests/mcap)"
  exit 77
fi

sed 's/^    rate: [0-9]*/    rate: 120/' "$source_dir/deploy/scenes/demo.yaml" >"$work/scene.yaml"
rec="$bin/panoptes_record"
"$rec" --out "$work/A.mcap" --quiet 2>"$work/A.log" &
a=$!
"$rec" --out "$work/B.mcap" --chunk-ms 300 --quiet 2>"$work/B.log" &
b=$!
"$rec" --idle --id rec_c --out "$work/C.mcap" --topics rt/panoptes/camera_status rt/panoptes/estimator_status \
  --quiet 2>"$work/C.log" &
c=$!
(ulimit -f 300; exec "$rec" --out "$work/D.mcap" --chunk-kb 64 --quiet 2>"$work/D.log") &
d=$!
pids+=("$a" "$b" "$c" "$d")
sleep 1
# The per-camera stream (not the live default): the recorded frames are compared with the estimator's records.
"$bin/panoptes_demo" --scene "$work/scene.yaml" --duration 8 --log-dir "$work/logs" --frames per-camera >"$work/demo.out" 2>&1 &
demo=$!
pids+=("$demo")
sleep 3
"$rec" --command start --target rec_c 2>"$work/cmd_start.log" && pass "DDS command started recorder C" ||
  { fail "start command"; cat "$work/cmd_start.log"; }
sleep 3
kill -KILL "$b"
"$rec" --command stop --target rec_c 2>"$work/cmd_stop.log" && pass "DDS command stopped recorder C" ||
  { fail "stop command"; cat "$work/cmd_stop.log"; }
timeout 60 tail -s 0.05 --pid="$demo" -f /dev/null
wait "$demo" || { fail "demo exit $?"; tail -5 "$work/demo.out"; }
sleep 1
kill -INT "$a"
timeout 20 "$rec" --command quit --target rec_c 2>/dev/null
wait_bounded "$a" 30 "recorder A" && pass "recorder A stopped cleanly on SIGINT" || fail "recorder A exit $?"
wait_bounded "$c" 30 "recorder C" && pass "recorder C quit on its DDS command" || fail "recorder C exit $?"
# D stops by itself when its file reaches the size limit; under heavy load the demo may not have
# produced 300 kB by now: bounded wait, then a clear failure rather than a hang.
timeout 30 tail -s 0.05 --pid="$d" -f /dev/null ||
  { echo "recorder D still running 30 s after the demo (the demo produced too little data?)"; kill -INT "$d"; }
wait_bounded "$d" 10 "recorder D"
rc_d=$?

# A: every message published is in the file; @mcap/core reads it.
check_mcap "$work/A.mcap" >"$work/A.json" && pass "@mcap/core reads A: $(json "$work/A.json" "d['messages']") messages, $(json "$work/A.json" "d['chunks']") chunks, CRCs, indexes and summary valid" ||
  { fail "@mcap/core on A"; cat "$work/A.json"; }
[ "$(json "$work/A.json" "len(d['schemas'])")" -ge 8 ] && [ "$(json "$work/A.json" "all(s['encoding']=='ros2idl' for s in d['schemas'])")" = True ] &&
  [ "$(json "$work/A.json" "d['profile']")" = ros2 ] && pass "ros2 profile, ros2idl schemas" || fail "profile or schemas wrong"
published=0
for log in "$work"/logs/cam*.log; do
  n=$(sed -n 's/.*stopped after \([0-9]*\) frames.*/\1/p' "$log" | tail -1)
  published=$((published + ${n:-0}))
done
features=$(json "$work/A.json" "d['topics'].get('/panoptes/features', 0)")
# The check is the equality; the floor only says the cameras ran the demo's 8 s. Idle, the four
# cameras publish about 4400 frames; beside the rest of the suite (ctest -j2) a starved camera drops
# frames in its queue, and a fresh-clone run published 2919 (cam0 551, 595 dropped), below the
# former floor of 3000: the floor is 1500.
[ "$published" -gt 1500 ] && [ "$features" -eq "$published" ] && pass "features: $features recorded = $published published by the cameras" ||
  fail "features: $features recorded, cameras published $published"
frames=$(frames_published "$work/logs/estimator_node.log")
for topic in tracks frames; do
  n=$(json "$work/A.json" "d['topics'].get('/panoptes/$topic', 0)")
  [ "$n" -eq "$frames" ] && pass "$topic: $n recorded = $frames published by the estimator" || fail "$topic: $n recorded, estimator published $frames"
done
[ "$(json "$work/A.json" "d['topics'].get('/panoptes/camera_info', 0)")" -eq 4 ] && pass "camera_info of the 4 cameras" || fail "camera_info count"
[ "$(json "$work/A.json" "d['topics'].get('/panoptes/estimator_status', 0)")" -ge 5 ] && pass "estimator_status recorded" || fail "estimator_status missing"

# The estimator offline from the recording = the offline JSONL path for the same features.
"$bin/panoptes_mcap_probe" "$work/A.mcap" --features-jsonl "$work/A_features.jsonl" >"$work/A_probe.json"
est="$bin/estimator_node --calibration $work/logs/calibration.yaml --quiet"
# Side by side: this test holds both cores (docs/testing.md).
$est --in-recording "$work/A.mcap" --out-tracks "$work/tracks_rec.jsonl" 2>"$work/est_rec.log" &
rec_run=$!
$est --no-dds --in-features "$work/A_features.jsonl" --out-tracks "$work/tracks_jsonl.jsonl" 2>"$work/est_jsonl.log"
wait "$rec_run"
if [ "$(wc -l <"$work/tracks_rec.jsonl")" -gt 3000 ] && cmp -s "$work/tracks_rec.jsonl" "$work/tracks_jsonl.jsonl"; then
  pass "estimator_node --in-recording: $(wc -l <"$work/tracks_rec.jsonl") track lines bit-identical to --in-features"
else
  fail "--in-recording tracks differ from the JSONL path"; tail -3 "$work/est_rec.log"
fi

# Foxglove's decoders: every channel of A read as its schema's type, every message decoded, and the
# fields equal to what was published (tests/tools/check_foxglove_decode.py says what is compared).
if node "$source_dir/tests/mcap/decode_ros2.mjs" "$work/A.mcap" --dump-dir "$work/A_foxglove" >"$work/A_foxglove.json"; then
  pass "Foxglove's ros2idl parser and CDR reader decode all $(json "$work/A_foxglove.json" "len(d['channels'])") channels of A as their schemas' types ($(json "$work/A_foxglove.json" "sum(c['decoded'] for c in d['channels'])") messages)"
else
  fail "Foxglove's decoders on A: $(json "$work/A_foxglove.json" "'; '.join(c['topic'] + ' ' + ', '.join(c['errors']) for c in d.get('channels', []) if c['errors']) or d.get('error')")"
fi
if /usr/bin/python3 "$source_dir/tests/tools/check_foxglove_decode.py" "$work/A_foxglove" --out-tracks "$work/logs/tracks.jsonl" \
  --features "$work/A_features.jsonl" --features-published "$published" --frames-published "$frames" \
  --calibration "$work/logs/calibration.yaml" --cameras cam0 cam1 cam2 cam3 --markers 3 >"$work/A_foxglove_check.txt"; then
  pass "Foxglove-decoded fields = what was published: $(grep -c '^ok' "$work/A_foxglove_check.txt") topics compared"
else
  fail "Foxglove-decoded fields differ from what was published"; cat "$work/A_foxglove_check.txt"
fi

# The filter tuner reads the recording directly (docs/recording.md, "Tune the filter").
if "$bin/estimator_node" tune --calibration "$work/logs/calibration.yaml" --in-recording "$work/A.mcap" \
  --params measurement_noise_px --sweeps 1 --out-config "$work/tuned.yaml" >"$work/tune.out" 2>&1 &&
  "$bin/estimator_node" --config "$work/tuned.yaml" --print-config >/dev/null 2>&1; then
  pass "estimator_node tune --in-recording wrote a config that loads: $(grep -o 'measurement_noise_px: [0-9.e-]*' "$work/tuned.yaml" | head -1)"
else
  fail "estimator_node tune --in-recording"; tail -3 "$work/tune.out"
fi

# B (SIGKILL): every complete chunk recovered, by our reader and by @mcap/core.
"$bin/panoptes_mcap_probe" "$work/B.mcap" >"$work/B.json"
check_mcap "$work/B.mcap" --allow-truncated >"$work/B_ref.json" || { fail "@mcap/core on B"; cat "$work/B_ref.json"; }
ours=$(json "$work/B.json" "d['messages']")
theirs=$(json "$work/B_ref.json" "d['messages']")
[ "$ours" -gt 500 ] && [ "$ours" -ge "$theirs" ] && pass "killed recorder B: $ours messages recovered (@mcap/core streams $theirs)" ||
  fail "B: ours $ours, @mcap/core $theirs"
last=$(json "$work/B.json" "d['last_log_time']['/panoptes/features']")
"$bin/panoptes_mcap_probe" "$work/A.mcap" --until-ns $((last - 20000000)) >"$work/A_until.json"
older=$(json "$work/A_until.json" "d['until']['/panoptes/features']")
recovered=$(json "$work/B.json" "d['topics']['/panoptes/features']")
[ "$recovered" -ge "$older" ] && pass "B holds every feature older than its last complete chunk ($recovered >= $older)" ||
  fail "B lost features before its last chunk: $recovered < $older"

# C (DDS commands) and D (file size limit).
check_mcap "$work/C.mcap" >"$work/C.json" && [ "$(json "$work/C.json" "d['topics'].get('/panoptes/camera_status', 0)")" -gt 0 ] &&
  [ "$(json "$work/C.json" "sorted(d['topics'])")" = "['/panoptes/camera_status', '/panoptes/estimator_status']" ] &&
  pass "C recorded its two topics between start and stop" || { fail "C"; cat "$work/C.json" "$work/C.log"; }
[ "$rc_d" -eq 1 ] && grep -q "cannot write" "$work/D.log" && pass "D stopped on the write error: $(grep -o 'cannot write.*' "$work/D.log" | head -1 | cut -c1-120)" ||
  { fail "D exit $rc_d"; cat "$work/D.log"; }
check_mcap "$work/D.mcap" >"$work/D.json" && [ "$(json "$work/D.json" "d['summary']")" = True ] &&
  pass "D's file is valid with its summary ($(json "$work/D.json" "d['messages']") messages)" || { fail "D's file"; cat "$work/D.json"; }

# Replay A's features and camera info into a live estimator: the original run's tracks again.
"$bin/estimator_node" --calibration "$work/logs/calibration.yaml" --out-tracks "$work/tracks_replay.jsonl" --duration 9 --quiet \
  2>"$work/est_live.log" &
live=$!
pids+=("$live")
# At 1x the replay keeps the original pace: panoptes_replay says "kept up" when no message left more
# than 20 ms late. Its first 5 s (3 s in stop 71 gave 353 frames to compare in one fresh check,
# under the > 400 asserted). Beside another test on two cores a few messages did (3 of 1338, 24.7 ms, at
# 1.00x overall): up to 1 % of them late, at 0.99x or better overall, passes too (issue 37).
"$bin/panoptes_replay" "$work/A.mcap" --topics /panoptes/features /panoptes/camera_info --end 5 \
  2>"$work/replay1.log"
replay_rc=$?
published=$(grep -oE "published [0-9]+ messages" "$work/replay1.log" | grep -oE "[0-9]+")
late=$(grep -oE "[0-9]+ messages more than 20 ms late" "$work/replay1.log" | grep -oE "^[0-9]+")
achieved=$(grep -oE "achieved [0-9.]+x" "$work/replay1.log" | grep -oE "[0-9.]+")
if grep -q "kept up" "$work/replay1.log" && [ "$replay_rc" -eq 0 ]; then
  pass "replay at 1x kept up: $(grep -o 'max lag [0-9.]* ms' "$work/replay1.log")"
elif [ -n "$published" ] && [ -n "$late" ] && [ -n "$achieved" ] && [ $((late * 100)) -le "$published" ] &&
  awk -v a="$achieved" 'BEGIN { exit !(a >= 0.99) }'; then
  pass "replay at 1x kept the pace: $late of $published messages more than 20 ms late, ${achieved}x"
else
  fail "replay at 1x (exit $replay_rc)"
  cat "$work/replay1.log"
fi
kill -INT "$live"
wait "$live"
shift=$(sed -n 's/.*shifted by \(-\?[0-9]*\) ns.*/\1/p' "$work/replay1.log")
/usr/bin/python3 - "$work/logs/tracks.jsonl" "$work/tracks_replay.jsonl" "${shift:-0}" >"$work/compare.txt" <<'PY'
import json, sys, math
def load(path, shift=0):
    by = {}
    for line in open(path):
        t = json.loads(line)
        if t.get("status") == "confirmed": by.setdefault(t["stamp_ns"] - shift, []).append(t["p"])
    return by
orig, rep = load(sys.argv[1]), load(sys.argv[2], int(sys.argv[3]))
common = sorted(set(orig) & set(rep))
d = sorted(min(math.dist(p, q) for q in orig[s]) for s in common for p in rep[s])
print(len(rep), len(common), d[len(d) // 2] if d else -1, d[int(len(d) * 0.95)] if d else -1)
PY
read -r n_rep n_common median p95 <"$work/compare.txt"
# The replayed run equals the original where frames arrive in the original order (median 0.0 m);
# where the machine delays some, the live estimator replays them late and its tracks differ by a
# little: stop 80's fresh check, beside a CPU-heavy unit test, had 288 replays (873 frames) and p95
# 0.68 mm, p99 1.44 mm, max 4.1 mm (p95 < 0.5 mm until then). A wrong replay (stamps, cameras,
# calibration) is off by centimetres or shares no stamps.
/usr/bin/python3 -c "import sys; sys.exit(0 if $n_common >= 0.9 * $n_rep and $n_rep > 400 and $median < 0.0001 and $p95 < 0.002 else 1)" &&
  pass "replayed live estimator: $n_common/$n_rep frames at the original stamps, distance to the original tracks median $median m, p95 $p95 m" ||
  fail "replayed tracks differ from the original run: $n_common/$n_rep stamps, median $median m, p95 $p95 m"
"$bin/panoptes_replay" "$work/A.mcap" --rate 10 --discovery 0.2 --quiet 2>"$work/replay10.log"
grep -qE "kept up|could not keep up" "$work/replay10.log" && pass "replay at --rate 10: $(grep -oE '(kept up|could not keep up).*' "$work/replay10.log")" ||
  { fail "replay at rate 10 said nothing"; cat "$work/replay10.log"; }

# Bad input: a clear error naming the file, never a crash.
: >"$work/empty.mcap"
expect_exit 2 "replay of an empty file" -- "$bin/panoptes_replay" "$work/empty.mcap"
expect_stderr_contains "empty.mcap: empty file" "empty file named"
cp "$work/A_features.jsonl" "$work/foreign.mcap"
expect_exit 2 "estimator_node --in-recording of a JSONL file" -- $est --in-recording "$work/foreign.mcap"
expect_stderr_contains "not an MCAP file" "foreign file named"
finish
