#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The planning budget of issue 19 (docs/planner.md, "Planning budget"): ten long runs
# of panoptes_plan with different seeds define the best quality; short runs with other seeds must
# each end within 2% of it. Budgets are CPU seconds of the planning process (--cpu-clock), so that
# a shared machine slows the runs down without shortening their search; runs go `jobs` at a time
# under nice. Prints one line per run and the verdict. The value compared is the search's objective
# (panoptes_plan's `objective <name> <value> m` line: tracker_rmse by default; OBJECTIVE=q for the
# seed's quality, as the 2026-11-27 figures were measured).
#   tests/bench/bench_plan_budget.sh <build dir> [room] [cameras] [long s] [short s] [short runs] [jobs]
#                                    [long runs' starts]
set -euo pipefail
build="${1:?build directory}"
room="${2:-$(dirname "$0")/../../deploy/planner/studio6x6.yaml}"
cameras="${3:-8}"
long_seconds="${4:-300}"
short_seconds="${5:-60}"
short_runs="${6:-3}"
jobs="${7:-2}"
long_starts="${8:-6}"
plan="$build/bin/panoptes_plan"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run() {  # SEED SECONDS STARTS: one plan, its output in $work/SEED.out
  nice -n 5 "$plan" --room "$room" --cameras "$cameras" --evaluations 100000000 --seconds "$2" --cpu-clock \
    --starts "$3" --seed "$1" --objective "${OBJECTIVE:-tracker_rmse}" --quiet >"$work/$1.out" 2>&1 || { echo "seed $1 failed:"; cat "$work/$1.out"; exit 1; }
}
quality() { sed -n 's/^objective [a-z_]* \([0-9.e-]*\) m$/\1/p' "$work/$1.out"; }
budget() { sed -n 's/^placed .* in \([0-9]*\) evaluations, \([0-9.]*\) s (\([0-9.]*\) CPU s).*/\1 evaluations, \2 s wall, \3 CPU s/p' "$work/$1.out"; }

queue() {  # SECONDS:STARTS:SEED...: every run, `jobs` at a time
  local running=0 item
  for item in "$@"; do
    IFS=: read -r seconds starts seed <<<"$item"
    run "$seed" "$seconds" "$starts" &
    running=$((running + 1))
    if [ "$running" -ge "$jobs" ]; then
      wait -n
      running=$((running - 1))
    fi
  done
  wait
}

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
long_seeds=$(seq 101 110)
short_seeds=$(seq 1 "$short_runs")
items=()
for s in $long_seeds; do items+=("$long_seconds:$long_starts:$s"); done
for s in $short_seeds; do items+=("$short_seconds:3:$s"); done
queue "${items[@]}"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"

best=$(for s in $long_seeds; do quality "$s"; done | sort -g | head -1)
for s in $long_seeds; do
  awk -v q="$(quality "$s")" -v b="$best" -v s="$s" -v o="${OBJECTIVE:-tracker_rmse}" -v u="$(budget "$s")" \
    'BEGIN { printf "long  seed %3d  %s %.6f m  %+6.2f%%  (%s)\n", s, o, q, 100 * (q / b - 1), u }'
done
verdict=0
for s in $short_seeds; do
  q=$(quality "$s")
  awk -v q="$q" -v b="$best" -v s="$s" -v o="${OBJECTIVE:-tracker_rmse}" -v u="$(budget "$s")" \
    'BEGIN { printf "short seed %3d  %s %.6f m  %+6.2f%%  (%s)\n", s, o, q, 100 * (q / b - 1), u }'
  awk -v q="$q" -v b="$best" 'BEGIN { exit !(q <= 1.02 * b) }' || verdict=1
done
[ "$verdict" -eq 0 ] && echo "every short run within 2% of the best long run (${best} m)" ||
  echo "a short run is more than 2% from the best long run (${best} m)"
exit "$verdict"
