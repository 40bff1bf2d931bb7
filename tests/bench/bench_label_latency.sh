#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The latency live labelling adds to the frames (issue 33, "bench_label": <= 0.1 ms added to the
# frame's p99, side by side with labelling off). test_live_labels's setup: the Gait2392 subject01
# model from its static trial, walk1 through walk8.yaml's eight asynchronous cameras with 0.3 false
# blobs per frame, replayed by camera_nodes into estimator_node over DDS (loopback profile) and read
# by panoptes_client_probe. Runs alternate labelling off and on (--subjects), RUNS of each, and
# print per mode the p50/p99/max of the frame's output stage (the filter update -> the frame was
# written, where the labelling stage runs) and of capture -> received, over every frame after the
# first second, with the runs pooled. A third mode, "names", labels without the segment poses
# (`subjects: segment_poses: false`), so the poses' own share shows (docs/marker_sets.md, "Segment
# poses live"). Last line: one JSON object.
#   tests/bench/bench_label_latency.sh <build dir> [runs (2)] [seconds per run (8)]
set -euo pipefail
build="$(cd "${1:?build directory}" && pwd)"
runs="${2:-2}"
seconds="${3:-8}"
root=$(cd "$(dirname "$0")/../.." && pwd)
bin="$build/bin"
data="$root/../shared/data/static"
for f in gait2392_subject01_static.trc gait2392_subject01_walk1.trc; do
  [ -f "$data/$f" ] || { echo "bench_label_latency: $data/$f is missing (../shared/data)" >&2; exit 2; }
done
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-23}"
export PANOPTES_DDS_PROFILE="${PANOPTES_DDS_PROFILE:-$root/deploy/dds/loopback.xml}"
work=$(mktemp -d)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; rm -rf "$work"' EXIT

"$bin/panoptes_label" model --static "$data/gait2392_subject01_static.trc" \
  --markerset "$root/deploy/markersets/gait2392.yaml" --out "$work/s1.yaml" --subject s1 >/dev/null
sed -e "s/^duration: .*/duration: $((seconds + 1)).0/" -e 's/^  false_blobs: .*/  false_blobs: 0.3/' \
  -e "s#^  file: .*#  file: $data/gait2392_subject01_walk1.trc#" -e 's/^  offset: .*/  offset: [-0.58, 0, 0]/' \
  "$root/deploy/scenes/walk8.yaml" >"$work/walk1.yaml"
"$bin/panoptes_sim" features --scene "$work/walk1.yaml" --out-dir "$work/sim" >/dev/null

run() {  # MODE INDEX: one live run; the probe's frames in $work/MODE.INDEX.jsonl
  local mode="$1" index="$2" args=() epoch
  [ "$mode" = off ] || args=(--subjects "$work/s1.yaml" --soft-segments Torso)
  [ "$mode" = names ] && args+=(--config "$work/no_segments.yaml")
  epoch=$((($(date +%s) + 3) * 1000000000))
  "$bin/panoptes_client_probe" --out "$work/$mode.$index.jsonl" --duration $((seconds + 5)) >/dev/null 2>&1 &
  local probe=$!
  "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" ${args[@]+"${args[@]}"} \
    --duration $((seconds + 4)) --quiet >"$work/$mode.$index.log" 2>&1 &
  local estimator=$!
  pids=("$probe" "$estimator")
  for camera in cam0 cam1 cam2 cam3 cam4 cam5 cam6 cam7; do
    "$bin/camera_node" --source "features:$work/sim/$camera.jsonl" --sim-epoch-ns "$epoch" --duration "$seconds" \
      --quiet >/dev/null 2>&1 &
    pids+=("$!")
  done
  wait "${pids[@]}" || true
  echo "bench_label_latency: run $index labelling $mode done" >&2
}

printf 'subjects:\n  segment_poses: false\n' >"$work/no_segments.yaml"
for ((i = 1; i <= runs; i++)); do
  run off "$i"
  run names "$i"
  run on "$i"
done

python3 - "$work" "$runs" <<'PY'
import glob, json, sys
work, runs = sys.argv[1], int(sys.argv[2])
def q(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(len(values) * p))] if values else float("nan")
result = {"runs": runs}
for mode in ("off", "names", "on"):
    output, total, labelled = [], [], 0
    for path in sorted(glob.glob(f"{work}/{mode}.*.jsonl")):
        frames = [json.loads(l) for l in open(path) if '"type":"frame"' in l]
        if not frames:
            continue
        first = frames[0]["stamp_ns"]
        for f in frames:
            if f["stamp_ns"] - first < 1e9:
                continue
            output.append(f["output_ns"] * 1e-6)
            total.append(f["capture_to_receive_ns"] * 1e-6)
            labelled += f.get("named", 0)
    row = {"frames": len(output), "named_marker_frames": labelled}
    for name, values in (("output", output), ("capture_to_receive", total)):
        row[name + "_ms"] = {k: round(q(values, p), 4) for k, p in (("p50", 0.5), ("p99", 0.99), ("max", 1.0))}
    result[mode] = row
    print(f"labelling {mode}: {row['frames']} frames ({labelled} named marker-frames); output stage "
          f"p50/p99/max {row['output_ms']['p50']:.3f}/{row['output_ms']['p99']:.3f}/{row['output_ms']['max']:.3f} ms; "
          f"capture->received {row['capture_to_receive_ms']['p50']:.3f}/{row['capture_to_receive_ms']['p99']:.3f}/"
          f"{row['capture_to_receive_ms']['max']:.3f} ms")
for stage in ("output_ms", "capture_to_receive_ms"):
    result["added_p99_" + stage] = round(result["on"][stage]["p99"] - result["off"][stage]["p99"], 4)
    result["names_added_p99_" + stage] = round(result["names"][stage]["p99"] - result["off"][stage]["p99"], 4)
print(f"added by labelling with segment poses at p99: output stage {result['added_p99_output_ms']:+.3f} ms, "
      f"capture->received {result['added_p99_capture_to_receive_ms']:+.3f} ms; names only: "
      f"{result['names_added_p99_output_ms']:+.3f} ms, {result['names_added_p99_capture_to_receive_ms']:+.3f} ms")
print(json.dumps(result))
PY
