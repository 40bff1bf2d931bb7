#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Issue 34 item 6, export what was seen live (docs/recording.md, "Export a recording"): a live
# simulated session with two rigid bodies (panoptes_demo on deploy/scenes/bodies.yaml cut to four
# cameras) recorded by panoptes_record; panoptes_export --in-recording then gives
#   - track records equal to the live estimator's --out-tracks (every line, every field),
#   - pose records equal to its --out-poses (every line, every field),
#   - marker files whose body-labelled markers are named <body>_<n> (head_0 .. tool_4);
# and panoptes_replay of that recording shifts every time of every topic by one offset: a second
# recorder's export of the replay holds the same records with stamps moved by the printed shift.
# LIVE test (DDS processes in the background).
source "$(dirname "$0")/lib.sh"
sed '/id: c[45],/d' "$source_dir/deploy/scenes/bodies.yaml" >"$work/scene.yaml"
topics="rt/panoptes/frames rt/panoptes/body_descriptions rt/panoptes/tracks rt/panoptes/bodies rt/panoptes/estimator_status"
# shellcheck disable=SC2086
"$bin/panoptes_record" --out "$work/A.mcap" --topics $topics --quiet 2>"$work/A.log" &
a=$!
pids+=("$a")
sleep 1
# The per-camera stream (not the live default): the recorded frames are compared with the estimator's records.
"$bin/panoptes_demo" --scene "$work/scene.yaml" --duration 8 --log-dir "$work/logs" --frames per-camera >"$work/demo.out" 2>&1 &
demo=$!
pids+=("$demo")
timeout 90 tail -s 0.05 --pid="$demo" -f /dev/null
wait "$demo" || { fail "demo exit $?"; tail -5 "$work/demo.out"; }
sleep 1
kill -INT "$a"
wait "$a" && pass "recorder stopped cleanly" || fail "recorder exit $?"

expect_exit 0 "export the recording: records as JSON Lines, markers as C3D and CSV, bodies as CSV" -- \
  "$bin/panoptes_export" --in-recording "$work/A.mcap" --out-tracks "$work/tracks.jsonl" --out-poses "$work/poses.jsonl" \
  --out "$work/take.c3d" --out "$work/take.csv" --bodies-csv "$work/bodies.csv"
cat "$work/last.out"
frames=$(frames_published "$work/logs/estimator_node.log")
/usr/bin/python3 - "$work/last.out" "$frames" <<'PY' && pass "every published frame is in the recording ($frames)" || fail "recorded frames differ from the $frames published: $(cat "$work/last.out")"
import json, sys
summary = json.loads(open(sys.argv[1]).read())
assert summary["recorded_frames"] == int(sys.argv[2]) > 500, summary
assert summary["skipped_records"] == 0, summary
PY

# The acceptance: the export equals the live --out-tracks and --out-poses records of the same run.
/usr/bin/python3 - "$work/logs/tracks.jsonl" "$work/tracks.jsonl" "$work/logs/poses.jsonl" "$work/poses.jsonl" \
  >"$work/compare.txt" 2>&1 <<'PY'
import json, sys
def load(path): return [json.loads(line) for line in open(path)]
live_t, exp_t, live_p, exp_p = (load(p) for p in sys.argv[1:5])
assert len(live_t) == len(exp_t) > 1000, ("track records", len(live_t), len(exp_t))
bad = [i for i, (a, b) in enumerate(zip(live_t, exp_t)) if a != b]
assert not bad, ("track records differ", len(bad), live_t[bad[0]], exp_t[bad[0]])
assert len(live_p) == len(exp_p) > 500, ("pose records", len(live_p), len(exp_p))
bad = [i for i, (a, b) in enumerate(zip(live_p, exp_p)) if a != b]
assert not bad, ("pose records differ", len(bad), live_p[bad[0]], exp_p[bad[0]])
print(len(exp_t), "track records and", len(exp_p), "pose records equal")
PY
[ $? -eq 0 ] && pass "export = live --out-tracks and --out-poses: $(cat "$work/compare.txt")" ||
  { fail "export differs from the live records"; cat "$work/compare.txt"; }

# Body markers carry names: head has 4 markers, tool 5 (deploy/scenes/bodies.yaml).
header=$(head -1 "$work/take.csv")
missing=""
for name in head_0 head_1 head_2 head_3 tool_0 tool_1 tool_2 tool_3 tool_4 head tool; do
  echo ",$header," | grep -q ",${name}_x," || missing="$missing $name"
done
[ -z "$missing" ] && pass "CSV names the labelled markers head_0..head_3, tool_0..tool_4 and the body origins" ||
  fail "CSV header lacks$missing: $(echo "$header" | cut -c1-300)"
grep -q '"labelled_markers": 9' "$work/last.out" && pass "the summary counts 9 labelled marker points" ||
  fail "labelled_markers: $(cat "$work/last.out")"
node "$source_dir/tests/c3d/read_c3d.js" "$work/take.c3d" >"$work/c3d.json" 2>&1 &&
  /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if {'head_0','tool_4'} <= set(d['labels']) else 1)" "$work/c3d.json" &&
  pass "the C3D's POINT:LABELS carry the names (independent reader)" || { fail "C3D labels"; head -c 300 "$work/c3d.json"; }

# Replay re-stamps every topic by one offset: record the replay and export it.
# shellcheck disable=SC2086
"$bin/panoptes_record" --out "$work/R.mcap" --topics $topics --quiet 2>"$work/R.log" &
r=$!
pids+=("$r")
sleep 1
"$bin/panoptes_replay" "$work/A.mcap" --end 3 2>"$work/replay.log" || { fail "replay exit $?"; cat "$work/replay.log"; }
sleep 1
kill -INT "$r"
wait "$r" || fail "replay recorder exit $?"
now_ns=$(date +%s%N)
shift=$(sed -n 's/.*shifted by \(-\?[0-9]*\) ns.*/\1/p' "$work/replay.log")
expect_exit 0 "export the recording of the replay" -- "$bin/panoptes_export" --in-recording "$work/R.mcap" \
  --out-tracks "$work/r_tracks.jsonl" --out-poses "$work/r_poses.jsonl"
/usr/bin/python3 - "$work/tracks.jsonl" "$work/r_tracks.jsonl" "$work/poses.jsonl" "$work/r_poses.jsonl" "${shift:-0}" "$now_ns" \
  >"$work/restamp.txt" 2>&1 <<'PY'
import json, sys
def load(path): return [json.loads(line) for line in open(path)]
orig_t, rep_t, orig_p, rep_p = (load(p) for p in sys.argv[1:5])
shift, now = int(sys.argv[5]), int(sys.argv[6])
assert shift > 0 and len(rep_t) > 100 and len(rep_p) > 50, (shift, len(rep_t), len(rep_p))
for orig, rep, key in ((orig_t, rep_t, "id"), (orig_p, rep_p, "body")):
    by = {(r["stamp_ns"], r[key]): r for r in orig}
    for r in rep:
        o = by.get((r["stamp_ns"] - shift, r[key]))
        assert o is not None, ("no original record at stamp - shift", r)
        assert o["p"] == r["p"], (o, r)
    assert abs(max(r["stamp_ns"] for r in rep) - now) < 10e9, "replayed stamps are not of the live clock"
print(len(rep_t), "track and", len(rep_p), "pose records of the replay at their original stamps +", shift, "ns")
PY
[ $? -eq 0 ] && pass "replay: $(cat "$work/restamp.txt")" || { fail "replayed stamps"; cat "$work/restamp.txt"; }
finish
