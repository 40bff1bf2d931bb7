#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Regenerates the tables of docs/benchmarks.md (between its bench-report markers) from the records in
# docs/bench-results/*.json; idempotent. --check only compares (exit 1 and a diff if they differ).
# A malformed record stops it with exit 2, naming the file, the row and the field.
# Usage: tests/bench/report.sh [--check] [--results DIR] [--doc FILE]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
check=()
common=()
while (($#)); do
  case "$1" in
    --check) check=(--check); shift ;;
    --results | --doc) common+=("$1" "$2"); shift 2 ;;
    -h | --help) sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "report.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
exec python3 "$here/bench_results.py" "${common[@]}" report "${check[@]}"
