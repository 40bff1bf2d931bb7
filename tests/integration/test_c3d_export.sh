#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# panoptes_export (docs/recording.md, "Export"): the walking data to C3D and TRC re-read by a
# second, independent C3D reader (tests/c3d/read_c3d.js, node) within 1e-6 m; a simulated session's
# offline tracks and poses exported at a fixed rate; bad input named with file and offset, also for
# --in-recording.
source "$(dirname "$0")/lib.sh"
walk="$source_dir/tests/data/walk_41markers_100hz.trc"
reader="$source_dir/tests/c3d/read_c3d.js"
command -v node >/dev/null || { fail "node is missing (deploy/install-deps.sh installs it)"; finish; }

# --- the walking data: C3D and TRC, read back by the other implementation -----------------------
expect_exit 0 "export the walking data to C3D, TRC and CSV" -- "$bin/panoptes_export" --markers "$walk" \
  --c3d "$work/walk.c3d" --trc "$work/walk.trc" --csv "$work/walk.csv"
node "$reader" "$work/walk.c3d" --trc "$walk" >"$work/walk.json" 2>"$work/node.err" || { fail "node reader failed"; cat "$work/node.err"; }
/usr/bin/python3 - "$work/walk.json" <<'PY' && pass "independent reader: 41 labelled points, 100 Hz, 238 frames, within 1e-6 m of the TRC" || fail "independent reader disagrees: $(cat "$work/walk.json")"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["processor"] == 84 and d["points"] == 41 and d["rate"] == 100 and d["frames"] == 238, d
assert d["labels"][0] == "R.Shoulder" and d["labels"][-1] == "L.Toe" and d["complete"], d
assert d["mismatched_validity"] == 0 and d["compared"] == 41 * 238, d  # the file has no gaps
assert d["max_error_m"] <= 1e-6, d
print("max_error_m", d["max_error_m"])
PY
cat "$work/walk.json" | head -c 200; echo
# Our TRC, converted by our C3D writer and read by node, still matches the original file.
expect_exit 0 "re-export our TRC as C3D" -- "$bin/panoptes_export" --markers "$work/walk.trc" --c3d "$work/walk2.c3d"
node "$reader" "$work/walk2.c3d" --trc "$walk" >"$work/walk2.json" 2>&1
/usr/bin/python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d["max_error_m"] <= 1e-6 and d["mismatched_validity"] == 0 else 1)' \
  "$work/walk2.json" && pass "TRC -> C3D -> independent reader within 1e-6 m" || fail "TRC round trip: $(cat "$work/walk2.json")"
[ "$(head -1 "$work/walk.csv" | tr ',' '\n' | wc -l)" -eq $((2 + 41 * 3)) ] && pass "CSV has frame, time and 41 x 3 columns" \
  || fail "CSV header: $(head -c 200 "$work/walk.csv")"

# --- a simulated session's offline outputs -------------------------------------------------------
scene="$source_dir/deploy/scenes/bodies.yaml"
expect_exit 0 "simulate 3 s of features" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 3
expect_exit 0 "offline estimator writes tracks and poses" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --bodies "$work/sim/bodies.yaml" --in-features "$work"/sim/c*.jsonl --no-dds --out-tracks "$work/tracks.jsonl" \
  --out-poses "$work/poses.jsonl" --quiet
expect_exit 0 "export tracks and poses at 100 Hz" -- "$bin/panoptes_export" --tracks "$work/tracks.jsonl" \
  --poses "$work/poses.jsonl" --rate 100 --c3d "$work/session.c3d" --trc "$work/session.trc" --csv "$work/session.csv" \
  --bodies-csv "$work/bodies.csv"
cat "$work/last.out"
node "$reader" "$work/session.c3d" --trc "$work/session.trc" >"$work/session.json" 2>&1
/usr/bin/python3 - "$work/session.json" "$work/last.out" "$work/bodies.csv" <<'PY' && pass "session C3D: independent reader agrees with our TRC; bodies CSV has quaternions" || fail "session export: $(head -c 300 "$work/session.json")"
import json, sys, csv
d = json.load(open(sys.argv[1]))
summary = json.loads(open(sys.argv[2]).read())
assert d["rate"] == 100 and d["points"] == summary["markers"] > 0 and d["frames"] == summary["frames"], (d, summary)
assert 290 <= d["frames"] <= 301, d  # 3 s at 100 Hz
assert d["mismatched_validity"] == 0 and d["compared"] > 0 and d["max_error_m"] <= 1e-6, d
rows = list(csv.DictReader(open(sys.argv[3])))
assert rows and set(["qx", "qy", "qz", "qw"]) <= set(rows[0]), rows[:1]
for r in rows:
    n = sum(float(r[k]) ** 2 for k in ("qx", "qy", "qz", "qw"))
    assert abs(n - 1) < 1e-6, r
PY

# --- y up (issue 34 item 2, docs/clients.md "Axis conventions") ----------------------------------
# The y-up files are the z-up files turned -90 degrees about x: (x, y, z) -> (x, z, -y) for every
# marker sample (C3D read back, TRC, CSV), and q' = q_R q for every body orientation, so each body
# axis is the z-up axis turned.
expect_exit 0 "export the walking data y up" -- "$bin/panoptes_export" --markers "$walk" --up-axis y \
  --c3d "$work/walk_y.c3d" --csv "$work/walk_y.csv"
expect_exit 0 "read the y-up C3D back as CSV" -- "$bin/panoptes_export" --markers "$work/walk_y.c3d" --csv "$work/walk_y_c3d.csv"
expect_exit 0 "export the session's bodies y up" -- "$bin/panoptes_export" --tracks "$work/tracks.jsonl" \
  --poses "$work/poses.jsonl" --rate 100 --up-axis Y --csv "$work/session_y.csv" --bodies-csv "$work/bodies_y.csv"
/usr/bin/python3 - "$work" <<'PY' && pass "y up: markers (CSV, C3D read back) and bodies are the z-up ones turned" || fail "y-up export differs from z up turned"
import csv, math, sys
w = sys.argv[1]
def table(name):
    return list(csv.reader(open(f"{w}/{name}")))
def check_markers(z_name, y_name, tolerance):
    z, y = table(z_name), table(y_name)
    assert z[0] == y[0] and len(z) == len(y) > 1, (z_name, y_name)
    worst = 0.0
    for rz, ry in zip(z[1:], y[1:]):
        for i in range(2, len(rz), 3):
            if rz[i] == "":
                assert ry[i] == "", (rz[:2], i)
                continue
            x, yy, zz = (float(v) for v in rz[i:i + 3])
            want = (x, zz, -yy)
            worst = max(worst, max(abs(float(a) - b) for a, b in zip(ry[i:i + 3], want)))
    assert worst <= tolerance, (z_name, y_name, worst)
    print(y_name, "max difference from z up turned", worst, "m")
check_markers("walk.csv", "walk_y.csv", 0.0)
check_markers("walk.csv", "walk_y_c3d.csv", 1e-6)  # C3D stores float32
check_markers("session.csv", "session_y.csv", 0.0)
def rot(q):  # x, y, z, w -> rows
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
turn = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]
bz = list(csv.DictReader(open(f"{w}/bodies.csv")))
by = list(csv.DictReader(open(f"{w}/bodies_y.csv")))
assert len(bz) == len(by) > 0
worst = 0.0
for a, b in zip(bz, by):
    assert (a["frame"], a["body"]) == (b["frame"], b["body"])
    p = [float(a[k]) for k in "xyz"]
    worst = max(worst, abs(float(b["x"]) - p[0]), abs(float(b["y"]) - p[2]), abs(float(b["z"]) + p[1]))
    rz = rot([float(a[k]) for k in ("qx", "qy", "qz", "qw")])
    ry = rot([float(b[k]) for k in ("qx", "qy", "qz", "qw")])
    want = [[sum(turn[i][k] * rz[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    worst = max(worst, max(abs(ry[i][j] - want[i][j]) for i in range(3) for j in range(3)))
assert worst <= 1e-5, worst  # the CSV's printed precision
print(len(by), "body rows, max difference", worst)
PY
expect_exit 2 "--up-axis x" -- "$bin/panoptes_export" --markers "$walk" --csv "$work/x.csv" --up-axis x
expect_stderr_contains "--up-axis=x: not an up axis (z or y)" "the error names --up-axis and the value"

# --- bad input ----------------------------------------------------------------------------------
expect_exit 2 "no input" -- "$bin/panoptes_export" --c3d "$work/x.c3d"
expect_exit 2 "no output" -- "$bin/panoptes_export" --markers "$walk"
head -c 700 "$work/walk.c3d" >"$work/cut.c3d"
expect_exit 2 "truncated C3D" -- "$bin/panoptes_export" --markers "$work/cut.c3d" --trc "$work/x.trc"
expect_stderr_contains "cut.c3d: offset " "the error names the file and the offset"
printf 'not json\n' >"$work/bad.jsonl"
expect_exit 2 "tracks file without a record" -- "$bin/panoptes_export" --tracks "$work/bad.jsonl" --c3d "$work/x.c3d"
expect_stderr_contains "bad.jsonl:1:" "the skipped line is named with file and line"
# A recording (--in-recording; its contents are checked by tools.ExportRecording.* and, live, by
# integration.test_export_recording): files that are not one, and options that need one.
expect_exit 2 "--in-recording of a JSON Lines file" -- "$bin/panoptes_export" --in-recording "$work/bad.jsonl" --out "$work/x.c3d"
expect_stderr_contains "bad.jsonl: byte 0: not an MCAP file" "the error names the file and what is wrong"
: >"$work/empty.mcap"
expect_exit 2 "--in-recording of an empty file" -- "$bin/panoptes_export" --in-recording "$work/empty.mcap" --out "$work/x.csv"
expect_stderr_contains "empty.mcap: empty file" "the empty file is named"
printf '\x89MCAP0\r\n\x01' >"$work/cut.mcap"
expect_exit 2 "--in-recording of a recording cut inside its header" -- "$bin/panoptes_export" --in-recording "$work/cut.mcap" \
  --out-tracks "$work/x.jsonl"
expect_stderr_contains "cut.mcap" "the cut file is named"
# A recording of features only (bench_recorder is built with PANOPTES_BUILD_BENCHMARKS).
if [ -x "$bin/bench_recorder" ]; then
  "$bin/bench_recorder" --cameras 1 --rate 10 --markers 2 --seconds 0.5 --fast-seconds 0.5 --keep "$work/features.mcap" \
    >"$work/bench_recorder.out" 2>&1 || fail "bench_recorder --keep: $(tail -2 "$work/bench_recorder.out")"
  expect_exit 2 "--in-recording of a recording without frames (features only)" -- "$bin/panoptes_export" \
    --in-recording "$work/features.mcap" --out "$work/x.c3d"
  expect_stderr_contains "features.mcap: no /panoptes/frames channel (the recording holds /panoptes/features)" \
    "the error names the file, the missing channel and what it holds"
else
  echo "note: no bench_recorder (PANOPTES_BUILD_BENCHMARKS=OFF): the recording without frames is left to tools.ExportRecording"
fi
expect_exit 2 "--out with an unknown extension" -- "$bin/panoptes_export" --in-recording "$work/cut.mcap" --out "$work/x.mcap"
expect_stderr_contains "--out" "the error names --out"
expect_exit 2 "--out-tracks without a recording" -- "$bin/panoptes_export" --tracks "$work/bad.jsonl" --out-tracks "$work/x.jsonl"
expect_stderr_contains "--out-tracks" "the error names --out-tracks"
expect_exit 2 "a recording and JSON Lines at once" -- "$bin/panoptes_export" --in-recording "$work/cut.mcap" \
  --tracks "$work/bad.jsonl" --out "$work/x.c3d"
expect_exit 0 "--help" -- "$bin/panoptes_export" --help
grep -q -- "--in-recording" "$work/last.out" && pass "--help lists --in-recording" || fail "--help lacks --in-recording"
finish
