#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# PTZ guidance (issue 22, seed 003 §2.3.3; docs/ptz.md): the walking actor of walk8.yaml, tracked
# by the estimator from 8 simulated cameras, is followed by a pan/tilt/zoom camera 5 m to the side
# (60°/s, 120°/s², 100 ms command latency) framing 0.5 m around the head (the clavicle marker
# raised 0.2 m: the recording has no head marker). Same tracks, same head, with and without
# prediction: the head must stay in the central half of the image >= 95% of the time with it, and
# clearly less without. Bad PTZ files and targets exit 2 naming the key.
source "$(dirname "$0")/lib.sh"
trc="$source_dir/tests/data/walk_41markers_100hz.trc"
ptz="$source_dir/deploy/ptz/walk_side.yaml"
json() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))$2)" "$1"; }

# 8 s of the walk (two reversals), trc path made absolute for the copy.
sed -e 's/^duration: 20.0/duration: 8.0/' -e "s#file: .*walk_41markers_100hz.trc#file: $trc#" \
  "$source_dir/deploy/scenes/walk8.yaml" >"$work/walk.yaml"
grep -q '^duration: 8.0' "$work/walk.yaml" || fail "could not shorten the scene"
expect_exit 0 "simulate 8 s of the walk" -- "$bin/panoptes_sim" features --scene "$work/walk.yaml" --out-dir "$work/sim"
expect_exit 0 "offline estimator" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --in-features "$work"/sim/cam*.jsonl --no-dds --out-tracks "$work/tracks.jsonl" --quiet
start=$(head -1 "$work/sim/truth.jsonl" | python3 -c "
import json, sys
m = [m for m in json.load(sys.stdin)['markers'] if m['name'] == 'trc/L.Clavicle'][0]['p']
print(','.join(str(v) for v in m))")

for mode in predicted plain; do
  flag=""; [ "$mode" = plain ] && flag="--no-prediction"
  expect_exit 0 "ptz_guide ($mode) from the tracks" -- "$bin/ptz_guide" --ptz "$ptz" --track-near "$start" \
    --offset 0,0,0.2 --in-tracks "$work/tracks.jsonl" --out "$work/commands_$mode.jsonl" $flag
  grep -q "following track" "$work/last.err" && pass "... follows a track ($(grep -c 'following track' "$work/last.err") pick(s))" ||
    fail "no track followed"
  expect_exit 0 "simulated PTZ camera ($mode)" -- "$bin/panoptes_sim" ptz --scene "$work/walk.yaml" --ptz "$ptz" \
    --commands "$work/commands_$mode.jsonl" --marker trc/L.Clavicle --offset 0,0,0.2 \
    --summary-json "$work/framing_$mode.json" --out-frames "$work/frames_$mode" --frames-every 2
done
with=$(json "$work/framing_predicted.json" "['central_half_fraction']")
without=$(json "$work/framing_plain.json" "['central_half_fraction']")
python3 -c "import sys; sys.exit(0 if $with >= 0.95 else 1)" &&
  pass "with prediction the head is in the central half $with of the time (>= 0.95)" || fail "with prediction: $with"
python3 -c "import sys; sys.exit(0 if $without <= $with - 0.3 else 1)" &&
  pass "without prediction only $without of the time" || fail "without prediction: $without (with: $with)"
n=$(ls "$work/frames_predicted"/*.pgm 2>/dev/null | wc -l)
[ "$n" -ge 3 ] && pass "$n images of the narrow view written" || fail "$n images of the narrow view"
# The image shows the head disc (grey, 110) near the centre: the mean column of its pixels.
python3 - "$(ls "$work/frames_predicted"/*.pgm | tail -1)" <<'PY' && pass "the head is drawn near the image centre" || fail "head not near the centre of the last view"
import sys
data = open(sys.argv[1], 'rb').read()
header = data.split(b'\n', 3)
w, h = map(int, header[1].split())
pixels = header[3]
cols = [i % w for i, v in enumerate(pixels) if v == 110]
rows = [i // w for i, v in enumerate(pixels) if v == 110]
sys.exit(0 if cols and abs(sum(cols) / len(cols) - w / 2) < w / 4 and abs(sum(rows) / len(rows) - h / 2) < h / 4 else 1)
PY

# Bad input: impossible limits, an unknown key, an unknown marker, no target.
printf 'ptz:\n  position: [0, -5, 1.6]\n  pan: {min_deg: 10, max_deg: -10}\n' >"$work/bad_limits.yaml"
expect_exit 2 "impossible pan limits are refused" -- "$bin/ptz_guide" --ptz "$work/bad_limits.yaml" --track-near 0,0,1 \
  --in-tracks "$work/tracks.jsonl"
grep -q "bad_limits.yaml: ptz.pan" "$work/last.err" && pass "... naming the file and key" || { fail "message"; cat "$work/last.err"; }
printf 'ptz:\n  position: [0, -5, 1.6]\n  zoom: {fov_min_deg: 2, fov_max_deg: 60, speed: 3}\n' >"$work/bad_key.yaml"
expect_exit 2 "an unknown key is refused" -- "$bin/panoptes_sim" ptz --scene "$work/walk.yaml" --ptz "$work/bad_key.yaml" \
  --commands "$work/commands_plain.jsonl" --marker trc/L.Clavicle
grep -q "ptz.zoom.speed" "$work/last.err" && pass "... naming the key" || { fail "message"; cat "$work/last.err"; }
expect_exit 2 "an unknown marker is refused" -- "$bin/panoptes_sim" ptz --scene "$work/walk.yaml" --ptz "$ptz" \
  --commands "$work/commands_plain.jsonl" --marker trc/Nose
grep -q "no marker 'trc/Nose'" "$work/last.err" && pass "... naming it" || { fail "message"; cat "$work/last.err"; }
expect_exit 2 "ptz_guide without a target is refused" -- "$bin/ptz_guide" --ptz "$ptz" --in-tracks "$work/tracks.jsonl"
finish
