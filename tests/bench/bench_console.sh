#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Console benchmark (issue 18, docs/benchmarks.md): panoptes_feature_flood publishes N cameras'
# FeatureFrames (640x480, B blobs each) at R Hz, their CameraInfo and status, and a TrackFrame per
# frame round, on the loopback profile; panoptes_console reads them and one chromium page shows them
# (tools/console/web/test/bench_console.mjs). Prints one JSON line: the console's CPU and
# WebSocket bandwidth, the page's frame rates, and beside them the publisher's CPU over the same
# seconds (the cost of writing the same samples to DDS). With [chains] > 0 the flood also writes a
# ChainFrame of that many finger chains after every camera frame, as estimator_node does.
#   tests/bench/bench_console.sh <build dir> <source dir> <cameras> [rate Hz] [blobs] [seconds] [synthetic tracks] [chains]
source "$(dirname "$0")/../integration/lib.sh"
cameras="${3:-4}"
rate="${4:-120}"
blobs="${5:-3}"
seconds="${6:-10}"
synthetic="${7:-0}"
chains="${8:-0}"
"$bin/panoptes_feature_flood" --cameras "$cameras" --rate "$rate" --blobs "$blobs" --chains "$chains" --duration $((seconds + 90)) \
  >"$work/flood.log" 2>&1 &
flood=$!
pids+=("$flood")
printf 'bench-console-token-%s\n' "$RANDOM$RANDOM$RANDOM" >"$work/token"
"$bin/panoptes_console" --bind 127.0.0.1:0 --token-file "$work/token" --url-file "$work/url" >"$work/console.log" 2>&1 &
console=$!
pids+=("$console")
for _ in $(seq 50); do [ -s "$work/url" ] && break; sleep 0.1; done
sleep 2
ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
flood_ticks0=$(ticks "$flood")
start=$(date +%s.%N)
extra=()
[ "$synthetic" -gt 0 ] && extra=(--synthetic-tracks "$synthetic")
result=$(node "$source_dir/tools/console/web/test/bench_console.mjs" --url "$(cat "$work/url")" \
  --console-pid "$console" --seconds "$seconds" "${extra[@]}")
flood_ticks1=$(ticks "$flood")
elapsed=$(echo "$(date +%s.%N) - $start" | bc)
flood_cpu=$(echo "scale=1; ($flood_ticks1 - $flood_ticks0) / $elapsed" | bc)
echo "{\"cameras\": $cameras, \"rate_hz\": $rate, \"blobs\": $blobs, \"chains\": $chains, \"publisher_cpu_percent\": $flood_cpu, \"load_average\": \"$(cut -d' ' -f1-3 /proc/loadavg)\", \"console\": $result}"
kill -INT "$flood" "$console" 2>/dev/null
wait "$flood" 2>/dev/null
tail -1 "$work/flood.log"
finish
