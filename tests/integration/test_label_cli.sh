#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# panoptes_label end to end, offline (docs/marker_sets.md, "Offline labelling"): a subject model from
# the Gait2392 static trial, then `run` on walk1 given as a C3D/TRC file and as the estimator's track
# JSON Lines (anonymous ids, occlusion gaps, false points); the labelled C3D read back by our reader
# (panoptes_export) and an independent one (tests/c3d/read_c3d.js) with the names in the model's
# order and every named sample equal to the walk's own marker of that name; gaps filled and
# reported per method; bad input refused with exit 2 naming the file or option.
source "$(dirname "$0")/lib.sh"
data="$source_dir/../shared/data/static"
require_shared_data "$data/gait2392_subject01_static.trc"
require_shared_data "$data/gait2392_subject01_walk1.trc"
set_yaml="$source_dir/deploy/markersets/gait2392.yaml"
walk="$data/gait2392_subject01_walk1.trc"

expect_exit 0 "model from the static trial" -- "$bin/panoptes_label" model --static "$data/gait2392_subject01_static.trc" \
  --markerset "$set_yaml" --out "$work/s1.yaml" --subject s1
expect_exit 0 "run --help shows the defaults" -- "$bin/panoptes_label" run --help
grep -q "max-gap-s FLOAT=0.3" "$work/last.out" && grep -q "fill TEXT=pattern" "$work/last.out" \
  && pass "--help: --max-gap-s 0.3, --fill pattern" || fail "--help lacks the defaults: $(cat "$work/last.out")"

# --- the walk's markers as anonymous columns (a TRC: its names are not read) ---------------------
expect_exit 0 "label walk1 (TRC in, C3D out)" -- "$bin/panoptes_label" run --tracks "$walk" --subjects "$work/s1.yaml" \
  --out "$work/walk.c3d" --report "$work/walk.json"
expect_exit 0 "read the labelled C3D back with our reader" -- "$bin/panoptes_export" --markers "$work/walk.c3d" \
  --trc "$work/back.trc"
/usr/bin/python3 - "$work/back.trc" "$walk" "$work/s1.yaml" "$work/walk.json" <<'PY' && pass "labelled C3D: names in the model's order, every walk marker named right within 1e-6 m" || fail "labelled C3D read back wrong"
import json, sys
def trc(path):
    lines = open(path).read().splitlines()
    names = [n for n in lines[3].split("\t")[2:] if n]
    rows = []
    for line in lines[5:]:
        fields = line.split("\t")
        if len(fields) < 2: continue
        rows.append([float(v) if v.strip() else None for v in fields[2:2 + 3 * len(names)]])
    return names, rows
back_names, back = trc(sys.argv[1])
walk_names, walk = trc(sys.argv[2])
# The model's tracked markers in its order: segments, then their markers (calibration-only left out).
expected, segment, calibration = [], None, False
for line in open(sys.argv[3]):
    s = line.strip()
    if s.startswith("- {name:") and "position_m" in s:
        name = s.split("name:")[1].split(",")[0].strip()
        if "calibration_only: true" not in s: expected.append(name)
assert back_names == expected, (back_names, expected)
assert len(back) == len(walk) == 151, (len(back), len(walk))
worst, compared = 0.0, 0
for m, name in enumerate(walk_names):
    b = back_names.index(name)
    for f in range(len(walk)):
        w = walk[f][3 * m:3 * m + 3]
        p = back[f][3 * b:3 * b + 3]
        if w[0] is None: continue
        assert p[0] is not None, (name, f)
        worst = max(worst, max(abs(x - y) for x, y in zip(p, w)) / 1000.0)
        compared += 1
assert worst <= 1e-6, worst
report = json.load(open(sys.argv[4]))
assert report["track_frames_labelled"] == report["track_frames"] == compared, (report, compared)
print("compared", compared, "samples, worst", worst, "m; names", len(back_names))
PY
if command -v node >/dev/null; then
  node "$source_dir/tests/c3d/read_c3d.js" "$work/walk.c3d" --trc "$work/back.trc" >"$work/node.json" 2>&1
  /usr/bin/python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d["labels"][0] == "R.ASIS" and d["points"] > 40 and d["rate"] == 60 and d["mismatched_validity"] == 0 and d["max_error_m"] <= 1e-6 else 1)' \
    "$work/node.json" && pass "independent reader: the same names and samples" || fail "independent reader: $(head -c 300 "$work/node.json")"
else
  fail "node is missing (deploy/install-deps.sh installs it)"
fi

# --- the estimator's track JSON Lines: new ids after gaps, false points; TRC and CSV outputs -----
/usr/bin/python3 - "$walk" "$work/tracks.jsonl" <<'PY'
import json, random, sys
random.seed(5)
lines = open(sys.argv[1]).read().splitlines()
names = [n for n in lines[3].split("\t")[2:] if n]
rows = [l.split("\t") for l in lines[5:] if len(l.split("\t")) > 2]
next_id, ids, hidden = 1, {}, {}
with open(sys.argv[2], "w") as out:
    for f, row in enumerate(rows):
        stamp = 1_000_000_000 + round(f * 1e9 / 60)
        for m, name in enumerate(names):
            if hidden.get(m, 0) > 0:
                hidden[m] -= 1
                ids.pop(m, None)
                continue
            if f > 10 and m in ids and random.random() < 0.01:
                hidden[m] = random.randint(3, 15)  # 50-250 ms hidden: a new id after
                ids.pop(m)
                continue
            if m not in ids:
                ids[m] = next_id
                next_id += 1
            p = [float(v) / 1000.0 for v in row[2 + 3 * m:5 + 3 * m]]
            out.write(json.dumps({"stamp_ns": stamp, "id": ids[m], "p": p, "v": [0, 0, 0]}) + "\n")
        if random.random() < 0.3:  # a false point for one frame
            out.write(json.dumps({"stamp_ns": stamp, "id": 100000 + f, "p": [0.5, 0.5, 2.5], "v": [0, 0, 0]}) + "\n")
PY
for fill in linear spline relational pattern none; do
  expect_exit 0 "label the tracks, --fill $fill" -- "$bin/panoptes_label" run --tracks "$work/tracks.jsonl" \
    --subjects "$work/s1.yaml" --rate-hz 60 --fill "$fill" --out "$work/tracks_$fill.trc" --report "$work/tracks_$fill.json"
done
expect_exit 0 "CSV output" -- "$bin/panoptes_label" run --tracks "$work/tracks.jsonl" --subjects "$work/s1.yaml" \
  --rate-hz 60 --out "$work/tracks.csv"
/usr/bin/python3 - "$work" <<'PY' && pass "JSON Lines tracks: labelled, gaps filled and counted per method, none with --fill none" || fail "JSON Lines run: see the reports in $work"
import json, sys
work = sys.argv[1]
r = {m: json.load(open(f"{work}/tracks_{m}.json")) for m in ("linear", "spline", "relational", "pattern", "none")}
for m, rep in r.items():
    assert rep["format"] == "tracks" and rep["frames"] in (151, 152), rep
    assert rep["track_frames_labelled"] >= 0.999 * rep["track_frames"] - 60, rep  # the false points stay unnamed
    print(m, json.dumps(rep["subjects"][0]["filled"]), "open", json.dumps(rep["subjects"][0]["left_open"]))
s = {m: rep["subjects"][0]["filled"] for m, rep in r.items()}
assert s["linear"]["linear"]["gaps"] > 0 and s["linear"]["spline"]["gaps"] == 0 == s["linear"]["relational"]["gaps"]
assert s["spline"]["spline"]["gaps"] > 0 and s["spline"]["linear"]["gaps"] == 0 == s["spline"]["relational"]["gaps"]
assert s["relational"]["relational"]["gaps"] > 0
assert s["relational"]["relational"]["gaps"] + s["relational"]["spline"]["gaps"] == s["linear"]["linear"]["gaps"]
assert s["pattern"]["pattern"]["gaps"] > 0 and s["pattern"]["linear"]["gaps"] == 0
assert sum(v["gaps"] for v in s["pattern"].values()) == s["linear"]["linear"]["gaps"]
assert s["relational"]["pattern"]["gaps"] == 0 == s["spline"]["pattern"]["gaps"]
assert all(v["gaps"] == 0 for v in s["none"].values())
PY
/usr/bin/python3 - "$work/tracks_none.trc" "$walk" "$work/tracks.jsonl" <<'PY' && pass "JSON Lines tracks: every named sample is the walk's marker of that name, >= 99 % named" || fail "JSON Lines tracks named wrong"
import json, sys
def trc(path):
    lines = open(path).read().splitlines()
    names = [n for n in lines[3].split("\t")[2:] if n]
    rows = [[float(v) if v.strip() else None for v in l.split("\t")[2:2 + 3 * len(names)]] for l in lines[5:] if len(l.split("\t")) > 1]
    return names, rows
out_names, out = trc(sys.argv[1])
walk_names, walk = trc(sys.argv[2])
real = sum(1 for line in open(sys.argv[3]) if json.loads(line)["id"] < 100000)
named = wrong = 0
for m, name in enumerate(walk_names):
    o = out_names.index(name)
    for f in range(min(len(out), len(walk))):
        p = out[f][3 * o:3 * o + 3]
        if p[0] is None: continue
        named += 1
        wrong += max(abs(x - y) for x, y in zip(p, walk[f][3 * m:3 * m + 3])) > 0.01  # mm
print("named", named, "of", real, "marker-frames,", wrong, "wrong")
assert wrong == 0 and named >= 0.99 * real, (named, real, wrong)
PY
head -1 "$work/tracks.csv" | grep -q "^frame,time_s,R.ASIS_x" && pass "CSV header names the markers" \
  || fail "CSV header: $(head -c 200 "$work/tracks.csv")"

# --- bad input ----------------------------------------------------------------------------------
expect_exit 2 "an unknown option" -- "$bin/panoptes_label" run --tracks "$walk" --subjects "$work/s1.yaml" \
  --out "$work/x.c3d" --gap 3
expect_stderr_contains "--gap" "the error names the option"
expect_exit 2 "a missing tracks file" -- "$bin/panoptes_label" run --tracks "$work/nope.jsonl" --subjects "$work/s1.yaml" \
  --out "$work/x.c3d"
expect_stderr_contains "nope.jsonl" "the error names the file"
expect_exit 2 "an unknown fill" -- "$bin/panoptes_label" run --tracks "$walk" --subjects "$work/s1.yaml" \
  --out "$work/x.c3d" --fill cubic
expect_stderr_contains "--fill" "the error names --fill"
expect_exit 2 "an output of an unknown kind" -- "$bin/panoptes_label" run --tracks "$walk" --subjects "$work/s1.yaml" \
  --out "$work/x.mp4"
expect_stderr_contains "--out" "the error names --out"
expect_exit 2 "a marker set given as the subject model" -- "$bin/panoptes_label" run --tracks "$walk" \
  --subjects "$set_yaml" --out "$work/x.c3d"
expect_stderr_contains "gait2392.yaml" "the error names the file"
expect_exit 2 "a marker set that does not match the static trial" -- "$bin/panoptes_label" model \
  --static "$data/gait2392_subject01_static.trc" --markerset "$source_dir/deploy/markersets/rajagopal.yaml" --out "$work/x.yaml"
expect_stderr_contains "gait2392_subject01_static.trc" "the error names the trial"
[ ! -e "$work/x.c3d" ] && [ ! -e "$work/x.yaml" ] && pass "nothing written on bad input" || fail "an output was written on bad input"
finish
