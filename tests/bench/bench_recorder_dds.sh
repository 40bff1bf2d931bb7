#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The whole recorder at the reference load over DDS (issue 17, docs/benchmarks.md): bench_recorder
# writes --fast-seconds of 32 cameras x 120 Hz x 40 markers as a recording; panoptes_replay
# publishes it at 1x while panoptes_record records every topic; the recorder's CPU time (utime +
# stime from /proc) over the replay, divided by the replay's wall time, is its share of one core.
#   bench_recorder_dds.sh <build dir> [seconds=15]
set -euo pipefail
build="$1"
seconds="${2:-15}"
export PANOPTES_DOMAIN="${PANOPTES_DOMAIN:-71}"
work="$(mktemp -d /tmp/panoptes-bench-recorder-XXXXXX)"
trap 'kill -INT "${rec:-0}" 2>/dev/null || true; rm -rf "$work"' EXIT
"$build/bin/bench_recorder" --fast-seconds "$seconds" --seconds 1 --keep "$work/load.mcap" >/dev/null
"$build/bin/panoptes_record" --out "$work/out.mcap" --quiet 2>"$work/rec.log" &
rec=$!
sleep 1
ticks() { awk '{print $14 + $15}' "/proc/$rec/stat"; }
hz=$(getconf CLK_TCK)
t0=$(date +%s.%N)
c0=$(ticks)
"$build/bin/panoptes_replay" "$work/load.mcap" --quiet 2>"$work/replay.log"
c1=$(ticks)
t1=$(date +%s.%N)
kill -INT "$rec"
wait "$rec" || true
rec=0
grep -E "kept up|could not" "$work/replay.log"
recorded=$(sed -n 's/.*rt\/panoptes\/features: \([0-9]*\)/\1/p' "$work/rec.log" | tail -1)
published=$(sed -n 's/.*rt\/panoptes\/features: \([0-9]*\)/\1/p' "$work/replay.log" | tail -1)
awk -v c0="$c0" -v c1="$c1" -v hz="$hz" -v t0="$t0" -v t1="$t1" -v r="$recorded" -v p="$published" 'BEGIN {
  printf "panoptes_record at 1x over DDS: %.1f%% of one core (%.2f s CPU over %.1f s); recorded %d of %d features\n",
    100 * (c1 - c0) / hz / (t1 - t0), (c1 - c0) / hz, t1 - t0, r, p }'
