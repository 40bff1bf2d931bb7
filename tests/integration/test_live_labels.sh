#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Live labelling over DDS (issue 33 item 2; docs/marker_sets.md, "Labels on the wire"): the
# Gait2392 subject01 model from its static trial; walk1 through the eight asynchronous cameras of
# walk8.yaml (self-occlusion, merging, 0.3 false blobs per frame) replayed by camera_nodes into
# estimator_node --subjects; a client (panoptes_client_probe) names the markers from
# rt/panoptes/labels and its view is scored against the simulator's truth: >= 99.5 % of the
# visible marker-frames named right and <= 0.1 % wrong after the first 0.5 s (outside the 500 ms
# after a gap in the estimator's input: a loaded machine, bounded apart), no left/right swap, two
# markers hidden for 0.6-0.8 s named again within 100 ms of their new tracks; a client started late
# has the names with its first frames (transient-local map); the run's recording exported to C3D
# names its points after the markers (read by tests/c3d/read_c3d.js); on a second, unscored replay
# the console's 3D view draws the names and the marker set's sticks (console_labels.png for
# docs/marker_sets.md).
# By hand: PANOPTES_LABELS_WALK=rajagopal runs the same with the Rajagopal walk (walk8's own) and its
# static trial and marker set; PANOPTES_LABELS_SEED=N sets the scene's seed (default walk8's, 8);
# PANOPTES_LABELS_SUBJECTS=2 plays walk1 twice (1.5 m apart, the second 0.7 s later, as
# test_label_two_subjects offline) with two models s1, s2, scored per subject (no name crosses).
source "$(dirname "$0")/lib.sh"
data="$source_dir/../shared/data/static"
probe="$bin/panoptes_client_probe"
score="$source_dir/tests/integration/score_labels.py"
walk_args=(-e "s#^  file: .*#  file: $data/gait2392_subject01_walk1.trc#" -e 's/^  offset: .*/  offset: [-0.58, 0, 0]/')
static="$data/gait2392_subject01_static.trc"
markerset="$source_dir/deploy/markersets/gait2392.yaml"
if [ "${PANOPTES_LABELS_WALK:-gait2392}" = rajagopal ]; then
  walk_args=(-e "s#^  file: .*#  file: $source_dir/tests/data/walk_41markers_100hz.trc#")
  static="$data/rajagopal_static_walk_1.trc"
  markerset="$source_dir/deploy/markersets/rajagopal.yaml"
else
  require_shared_data "$data/gait2392_subject01_walk1.trc"
fi
require_shared_data "$static"
[ -z "${PANOPTES_LABELS_SEED:-}" ] || walk_args+=(-e "s/^seed: .*/seed: $PANOPTES_LABELS_SEED/")

subjects=(s1)
[ "${PANOPTES_LABELS_SUBJECTS:-1}" = 2 ] && subjects=(s1 s2)
mkdir -p "$work/models"
for s in "${subjects[@]}"; do
  expect_exit 0 "model $s from the static trial" -- "$bin/panoptes_label" model \
    --static "$static" --markerset "$markerset" --out "$work/models/$s.yaml" --subject "$s"
done
# The subjects as settings (`subjects:` in --config; a model's path is relative to the file).
models=$(printf 'models/%s.yaml, ' "${subjects[@]}")
printf 'subjects:\n  models: [%s]\n  soft_segments: [Torso]\n' "${models%, }" >"$work/settings.yaml"

# walk8's cameras and effects, walk1 instead of the 41-marker walk, 0.3 false blobs per frame.
scene="$work/walk1.yaml"
sed -e 's/^duration: .*/duration: 10.0/' -e 's/^  false_blobs: .*/  false_blobs: 0.3/' "${walk_args[@]}" \
  "$source_dir/deploy/scenes/walk8.yaml" >"$scene"
score_args=()
segment_args=()
if [ "${#subjects[@]}" = 2 ]; then
  sed -i '/^trc:/,$d' "$scene"
  walk1="$data/gait2392_subject01_walk1.trc"
  cat >>"$scene" <<YAML
trc:
  - {file: $walk1, prefix: s1/, offset: [-0.58, -0.75, 0], turnaround: 0.5, start: 0.125, occlusion: {facing_angle: 100}}
  - {file: $walk1, prefix: s2/, offset: [-0.58, 0.75, 0], turnaround: 0.5, start: 0.825, occlusion: {facing_angle: 100}}
YAML
  score_args=(--by-subject)
elif [ "${PANOPTES_LABELS_WALK:-gait2392}" = gait2392 ]; then
  # Two markers hidden from every camera for longer than the tracker keeps a coasting track: each
  # comes back under a new track, and its name must be back within 100 ms (issue 33; offline with
  # more seeds: test_label_occlusion.sh).
  printf '  hide:\n    - {marker: L.Shank.Front, from: 3.0, to: 3.8}\n    - {marker: L.Wrist.Lat, from: 6.0, to: 6.6}\n' >>"$scene"
  score_args=(--hidden L.Shank.Front:3.8 --hidden L.Wrist.Lat:6.6 --max-reappear-ms 100)
  # Hidden, a marker is missing from the truth: the segment scoring leaves those intervals out (and
  # 0.2 s after, for the name and the pose to come back).
  segment_args=(--skip-between 3.0:4.0 --skip-between 6.0:6.8)
fi
expect_exit 0 "simulate walk1 through eight cameras" -- "$bin/panoptes_sim" features --scene "$scene" \
  --out-dir "$work/sim"

epoch=$(($(date +%s%N) + 3000000000))  # 3 s ahead (a whole second 3-4 s ahead until stop 71)
echo "$epoch" >"$work/epoch"  # for the scoring of a kept run by hand
"$probe" --out "$work/client.jsonl" --out-labels "$work/client_labels.jsonl" --duration 16 \
  >"$work/client.log" 2>&1 &
client=$!
pids+=("$client")
# The recording of the live run, exported with the names (rt/panoptes/labels, docs/recording.md).
"$bin/panoptes_record" --out "$work/live.mcap" --topics rt/panoptes/frames rt/panoptes/labels --quiet \
  2>"$work/record.log" &
recorder=$!
pids+=("$recorder")
# The per-camera stream (not the live default): the recorded frames' names are compared with --out-labels.
"$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --config "$work/settings.yaml" --frames per-camera \
  --out-labels "$work/estimator_labels.jsonl" --duration 15 >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
replay_cameras "$epoch" 14 cam0 cam1 cam2 cam3 cam4 cam5 cam6 cam7
camera_pids=("${pids[@]: -8}")
# A late client: started while the subject is labelled, it gets the map (transient-local) at once.
sleep 7
late_start_ns=$(date +%s%N)
"$probe" --out "$work/late.jsonl" --out-labels "$work/late_labels.jsonl" --duration 4 >"$work/late.log" 2>&1 &
late=$!
pids+=("$late")
# The replay ends with the scene's features: SIGINT then ends the estimator and the client as
# their --duration would (the same summaries), ~3 s sooner, once the last frames had 0.5 s.
for pid in "${camera_pids[@]}"; do timeout 30 tail -s 0.05 --pid="$pid" -f /dev/null; done
sleep 0.5
kill -INT "$estimator" 2>/dev/null
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null
expect_clean_exit "$estimator" estimator_node "$work/estimator.log"
sleep 0.3
kill -INT "$client" 2>/dev/null
timeout 20 tail -s 0.05 --pid="$client" -f /dev/null
timeout 20 tail -s 0.05 --pid="$late" -f /dev/null
# The scoring below (CPU-bound, ~10 s one after another) starts now, in the background, while the
# recording is exported and the console is checked: this test holds both cores (docs/testing.md).
declare -A scoring
for who in client estimator; do
  /usr/bin/python3 "$score" "$work/${who}_labels.jsonl" "$work/sim/truth.jsonl" --skip-s 0.5 \
    --truth-shift-ns $((epoch - 1700000000000000000)) --min-right 99.5 --max-wrong 0.1 "${score_args[@]}" \
    --gaps-from "$work/estimator_labels.jsonl" --gap-ms 25 --max-wrong-after-gap 10 --max-after-gap-s 2 \
    --explain 8 >"$work/${who}_score.json" 2>"$work/${who}_score.err" &
  scoring[$who]=$!
done
/usr/bin/python3 "$source_dir/tests/integration/score_segments.py" "$work/client.jsonl" "$work/sim/truth.jsonl" \
  --truth-shift-ns $((epoch - 1700000000000000000)) --skip-s 0.5 --every 10 --exclude Torso \
  --max-rms-mm 10 --min-posed 95 --gaps-from "$work/estimator_labels.jsonl" --gap-ms 25 "${segment_args[@]}" >"$work/segments.json" 2>&1 &
scoring[segments]=$!
grep "^estimator_node: labels:" "$work/estimator.log" || true
kill -INT "$recorder" 2>/dev/null
wait "$recorder" && pass "recorder stopped cleanly" || fail "recorder exit $?"
expect_exit 0 "export the live recording to C3D" -- "$bin/panoptes_export" --in-recording "$work/live.mcap" \
  --out "$work/live.c3d"
# Read back by the independent reader: every name the estimator gave is a point of the C3D.
node "$source_dir/tests/c3d/read_c3d.js" "$work/live.c3d" >"$work/c3d.json" 2>&1
/usr/bin/python3 - "$work/c3d.json" "$work/estimator_labels.jsonl" <<'PY' && pass "the exported C3D names every marker the estimator named" || fail "the exported C3D's names: $(head -c 300 "$work/c3d.json")"
import json, sys
labels = set(json.load(open(sys.argv[1]))["labels"])
records = [json.loads(line) for line in open(sys.argv[2])]
several = len({t["subject"] for r in records for t in r["tracks"] if t.get("subject")}) > 1
# Several subjects: C3D points are "<subject>:<marker>" (export, docs/marker_sets.md).
named = {(t["subject"] + ":" if several else "") + t["marker"] for r in records for t in r["tracks"] if t.get("marker")}
print(f"C3D points named after markers: {len(named & labels)} of the {len(named)} names the estimator gave")
sys.exit(0 if len(named) >= 41 and named <= labels else 1)
PY
# The console's 3D view with the names and sticks (tools/console/web/test/console_labels_test.mjs),
# when a browser is installed (required under CI, like every browser test), on a second replay of
# the walk's first seconds by a second estimator (its names in console_labels.jsonl), once the
# page has loaded (--ready-file). Not during the scored walk: with the page live beside the eight
# cameras, the camera_nodes' frames reached the estimator up to 0.3-1 s late (p99; 4-8 ms without
# it) and 250-2700 of 8000 were dropped, even with chromium at SCHED_IDLE, drawing at 5 Hz and the
# console's snapshots at 5 Hz; and started with the walk, the page took 6-13 s to load (stop 72).
if have_browser "console part"; then
  shots="${PANOPTES_CONSOLE_SHOTS:-$work/shots}"
  mkdir -p "$shots"
  start_console labels --update-rate 10
  timeout 45 node "$web/test/console_labels_test.mjs" --url "$url&fps=10" --out "$work/browser.json" --shots "$shots" \
    --ready-file "$work/page_loaded" >"$work/browser.out" 2>&1 &
  browser=$!
  pids+=("$browser")
  for _ in $(seq 300); do [ -s "$work/page_loaded" ] || ! kill -0 "$browser" 2>/dev/null && break; sleep 0.1; done
  [ -s "$work/page_loaded" ] && pass "console page loaded in chromium" || fail "console page not loaded within 30 s"
  epoch=$(($(date +%s%N) + 3000000000))
  "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --config "$work/settings.yaml" \
    --out-labels "$work/console_labels.jsonl" --duration 20 >"$work/console_estimator.log" 2>&1 &
  console_estimator=$!
  pids+=("$console_estimator")
  replay_cameras "$epoch" 10 cam0 cam1 cam2 cam3 cam4 cam5 cam6 cam7
  camera_pids=("${pids[@]: -8}")
  wait "$browser" && pass "console: names and sticks drawn" || fail "console: names and sticks (exit $?)"
  cat "$work/browser.out"
  kill -INT "${camera_pids[@]}" 2>/dev/null
  for pid in "${camera_pids[@]}"; do timeout 10 tail -s 0.05 --pid="$pid" -f /dev/null; done
  kill -INT "$console_estimator" 2>/dev/null
  wait_bounded "$console_estimator" 20 "the console phase's estimator_node" >/dev/null
  # Every (track, name) the page drew is one that estimator wrote (--out-labels).
  /usr/bin/python3 - "$work/browser.json" "$work/console_labels.jsonl" <<'PY' &&
import json, sys
shown = {tuple(pair) for pair in json.load(open(sys.argv[1])).get("names", [])}
written = set()
for line in open(sys.argv[2]):
    for t in json.loads(line)["tracks"]:
        if t.get("marker"):
            written.add((t["track"], t["marker"]))
print(f"the page showed {len(shown)} (track, name) pairs; {len(shown & written)} of them in the estimator's labels")
sys.exit(0 if shown and shown <= written else 1)
PY
    pass "the console's names are the estimator's" || fail "the console showed names the estimator did not write"
fi

# The client's view, scored like the estimator's own --out-labels (the same format). The issue's
# bounds hold while the estimator's input flows. A machine too loaded to run eight cameras beside
# another test (the README's ctest -j2 on 2 cores) can stall every camera_node at once: after such a
# gap (no frame for > 25 ms: what the tracker takes for a pause of its input, 50 ms until stop 71)
# the tracker holds the markers' tracks back and reacquires them, and the labeller names new ones
# again (docs/estimator.md, "After every camera stalled"). The 500 ms after a gap are scored apart,
# with a bound of their own, and may cover at most 2 s of the walk (docs/testing.md, "Live tests
# under load").
for who in client estimator; do
  if wait "${scoring[$who]}"; then
    pass "$who: names right and wrong within the issue's bounds: $(cat "$work/${who}_score.json")"
  else
    fail "$who: names: $(cat "$work/${who}_score.json" "$work/${who}_score.err")"
    if [ "$who" = estimator ]; then
      # The labeller's share: the estimator's own tracks labelled again at every record, offline
      # (docs/marker_sets.md, "When a live run names wrongly").
      "$bin/panoptes_label_replay" --labels "$work/estimator_labels.jsonl" --subjects "$work"/models/*.yaml \
        --out "$work/replayed_labels.jsonl" >/dev/null 2>&1 &&
        echo "  the same tracks labelled at every record offline: $(/usr/bin/python3 "$score" \
          "$work/replayed_labels.jsonl" "$work/sim/truth.jsonl" --skip-s 0.5 "${score_args[@]}" \
          --truth-shift-ns $((epoch - 1700000000000000000)) 2>&1)"
    fi
  fi
done
if [ "${#subjects[@]}" = 2 ]; then
  crossings=$(jq -r '.subject_crossings' "$work/client_score.json" 2>/dev/null)
  [ "${crossings:-x}" = 0 ] && pass "no name crosses subjects in the client's names" ||
    fail "names crossing subjects in the client's names: ${crossings:-not reported}"
fi
# Segment poses (docs/marker_sets.md, "Segment poses live"): the client receives each segment as a
# body "<subject>/<segment>" with its description; posed, the described markers lie where the true
# markers were (the soft Torso left out).
if wait "${scoring[segments]}"; then
  pass "segment poses at the client: $(jq -c '{segments_described, worst_rms_mm, least_posed_percent}' "$work/segments.json")"
else
  fail "segment poses at the client: $(cat "$work/segments.json")"
fi
swaps=$(jq -r '.left_right_swaps' "$work/client_score.json" 2>/dev/null)
[ "${swaps:-x}" = 0 ] && pass "no left/right swap in the client's names" ||
  fail "left/right swaps in the client's names: ${swaps:-not reported}"
stats=$(grep '"type":"stats"' "$work/client.jsonl" | tail -n 1)
echo "$stats" | jq -e '.labels_received >= 1 and .labels_malformed == 0' >/dev/null &&
  pass "the client received $(echo "$stats" | jq .labels_received) label maps, none malformed" ||
  fail "client label maps: $stats"

# The wire: the client's names are the estimator's own (--out-labels) for the same frames; a frame
# that overtook the map naming a new track may differ (the map is its own topic). Compared from the
# client's first map on: discovery matches each topic's reader on its own, and under load the
# client's labels reader matched 117 ms after its frames reader (its first 0.12 s of frames had no
# names, 1.2 % of the pairs); that wait is bounded as the late client's below (250 ms).
/usr/bin/python3 - "$work/client_labels.jsonl" "$work/estimator_labels.jsonl" <<'PY' && pass "the client's names are the estimator's" || fail "the client's names differ from the estimator's"
import json, sys
def names(path):
    out = {}
    for line in open(path):
        if line.strip():
            r = json.loads(line)
            out[r["stamp_ns"]] = {t["track"]: t.get("marker") for t in r["tracks"] if t.get("marker")}
    return out
client, estimator = names(sys.argv[1]), names(sys.argv[2])
named = sorted(s for s in client if client[s])
common = [s for s in client if s in estimator and named and s >= named[0]]
if named:
    print(f"the client's first names on its frame {(named[0] - min(client)) * 1e-6:.0f} ms after its first frame")
pairs = same = 0
for s in common:
    for track, marker in estimator[s].items():
        pairs += 1
        same += client[s].get(track) == marker
print(f"{len(common)} frames in both, {same} of {pairs} named markers named alike")
# From the estimator's first names: the labeller's own start, which a loaded machine delays, is not
# the wire's (stop 72: both named first 456 ms after their first frame, on the same frame).
first = min((s for s in estimator if estimator[s]), default=None)
waited = named and first is not None and named[0] - first < 250_000_000
sys.exit(0 if waited and len(common) > 100 and pairs > 0 and same >= 0.99 * pairs else 1)
PY

# The late client: its first frames carry names (the map is transient-local).
/usr/bin/python3 - "$work/late_labels.jsonl" "$late_start_ns" <<'PY' && pass "a late client names markers from its first frames on" || fail "the late client's names"
import json, sys
records = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
start = int(sys.argv[2])
named = [r for r in records if any("marker" in t for t in r["tracks"])]
print(f"late client: {len(records)} frames, {len(named)} with names; first frame "
      f"{(records[0]['stamp_ns'] - start) * 1e-6 if records else -1:.0f} ms after it started, first named "
      f"{(named[0]['stamp_ns'] - records[0]['stamp_ns']) * 1e-6 if named else -1:.0f} ms after that")
sys.exit(0 if len(records) > 50 and named and named[0]["stamp_ns"] - records[0]["stamp_ns"] < 250_000_000 else 1)
PY
finish
