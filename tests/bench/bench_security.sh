#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# bench_security: what DDS Security costs the live pipeline (docs/security.md, "Secure
# vs plain latency" and "Cost"). bench_latency on the loopback profile, plain and secured
# (a throw-away studio of deploy/security/panoptes-security, governance ENCRYPT by default),
# alternated ROUNDS times in one run so both see the same machine; prints one JSON object with
# every run and the medians' ratios (secure / plain). With --variant-profile FILE a third run per
# round, secured with that DDS profile (e.g. crypto properties such as
# dds.sec.crypto.maxblockspersession), is compared with the same plain runs.
# The goal "≤ 1.3× the plain ratio" has two readings, both printed: secure / plain of the
# end-to-end latency ("secure_over_plain"), and secure / plain of bench_latency's
# ratio_vs_dds_floor, whose floor is measured through the same (secured or plain) participants
# ("floor_ratio_secure_over_plain").
#   tests/bench/bench_security.sh BUILD_DIR [ROUNDS=2] [--protection encrypt|sign|payload|submessage]
#       [--variant-profile FILE] [bench_latency options...]
set -euo pipefail
build_dir="${1:?usage: bench_security.sh BUILD_DIR [ROUNDS] [--protection encrypt|sign|payload|submessage] [bench_latency options]}"
rounds="${2:-2}"
shift $(($# >= 2 ? 2 : 1))
protection=encrypt
if [ "${1:-}" = "--protection" ]; then protection="${2:?}"; shift 2; fi
variant_profile=""
if [ "${1:-}" = "--variant-profile" ]; then variant_profile="$(realpath "${2:?}")"; shift 2; fi
modes=(plain secure)
[ -n "$variant_profile" ] && modes+=(secure_variant)
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
tool="$source_dir/deploy/security/panoptes-security"
scene="$source_dir/deploy/scenes/latency240.yaml"
work="$(mktemp -d /tmp/bench-security-XXXXXX)"
trap 'rm -rf "$work"; bash "$source_dir/deploy/dds-shm-clean.sh" >/dev/null 2>&1 || true' EXIT

"$tool" init "$work/studio" --protection "$protection" >/dev/null
"$tool" issue "$work/studio" estimator estimator >/dev/null
"$tool" issue "$work/studio" console console >/dev/null
for camera in $(sed -n 's/^  - id: \(cam[0-9]*\)$/\1/p' "$scene"); do
  "$tool" issue "$work/studio" camera "$camera" >/dev/null
done
for round in $(seq 1 "$rounds"); do
  for mode in "${modes[@]}"; do
    extra=()
    [ "$mode" != plain ] && extra=(--security-dir "$work/studio")
    [ "$mode" = secure_variant ] && extra+=(--dds-profile "$variant_profile")
    echo "bench_security: round $round, $mode" >&2
    "$build_dir/bin/bench_latency" --json --scene "$scene" "${extra[@]}" "$@" >"$work/$mode-$round.json" 2>"$work/$mode-$round.log" ||
      { echo "bench_security: bench_latency ($mode) failed:" >&2; tail -5 "$work/$mode-$round.log" >&2; exit 1; }
  done
done
python3 - "$work" "$rounds" "$protection" "$variant_profile" "${modes[@]}" <<'PY'
import json, statistics, sys
work, rounds, protection, variant_profile, modes = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5:]
runs = {m: [json.load(open(f"{work}/{m}-{r}.json")) for r in range(1, rounds + 1)] for m in modes}
def pick(run):
    cpu = run.get("cpu_while_measuring") or {}
    return {"end_to_end_p50_ms": run["end_to_end_ms"]["p50"], "end_to_end_p99_ms": run["end_to_end_ms"]["p99"],
            "transport_in_p50_ms": run["breakdown_ms"]["transport_camera_to_estimator"]["p50"],
            "transport_out_p50_ms": run["breakdown_ms"]["transport_estimator_to_subscriber"]["p50"],
            "dds_two_hops_p50_ms": run["dds_floor_ms"]["two_hops"]["p50"],
            "dds_two_hops_p99_ms": run["dds_floor_ms"]["two_hops"]["p99"],
            "ratio_vs_dds_floor_p50": run["ratio_vs_dds_floor_p50"],
            "ratio_vs_dds_floor_p99": run["ratio_vs_dds_floor_p99"],
            "poses_per_s": run["poses_per_s"], "pipeline_cores": cpu.get("pipeline_cores"),
            "host_busy_cores": cpu.get("host_busy_cores")}
table = {m: [pick(r) for r in rs] for m, rs in runs.items()}
median = {m: {k: statistics.median(x[k] for x in rows) for k in rows[0]} for m, rows in table.items()}
def over_plain(mode):
    return {k: median[mode][k] / median["plain"][k] for k in median["plain"] if median["plain"][k]}
def minus_plain(mode):
    return {k: median[mode][k] - median["plain"][k] for k in median["plain"]}
result = {"benchmark": "bench_latency secure vs plain (loopback, latency240: 4 cameras x 240 Hz)",
          "rtps_protection": protection.upper(), "rounds": rounds, "runs": table, "median": median,
          "secure_over_plain": over_plain("secure"), "secure_minus_plain": minus_plain("secure")}
if variant_profile:
    result.update({"variant_profile": variant_profile, "variant_over_plain": over_plain("secure_variant"),
                   "variant_over_secure": {k: median["secure_variant"][k] / median["secure"][k]
                                           for k in median["secure"] if median["secure"][k]}})
# The literal reading of "≤ 1.3x the plain ratio": each run's end-to-end / DDS-floor ratio, secure
# over plain (the floor of a secure run crosses the same secured participants).
result["floor_ratio_secure_over_plain"] = {
    m: {q: median[m][f"ratio_vs_dds_floor_{q}"] / median["plain"][f"ratio_vs_dds_floor_{q}"]
        for q in ("p50", "p99")} for m in modes if m != "plain"}
print(json.dumps(result, indent=2))
PY
