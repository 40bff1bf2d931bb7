#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A bad PANOPTES_DOMAIN (issue 31, docs/protocol.md "The domain"): every program in build/bin that
# opens DDS, run with PANOPTES_DOMAIN=abc and =300, exits 2 with one line naming the variable and
# the value, before any participant exists (the bus used to read it with atoi: "abc" joined domain
# 0, and Fast DDS exited the process by itself for 300). The C++ client (panoptes_client_probe and
# the examples) and the Python client throw naming it. A program in build/bin that links Fast DDS
# or the client library but is missing from the table below fails the test.
# A missing DDS profile (PANOPTES_DDS_PROFILE naming no file) is bad input too: every program in
# the table that loads a Fast DDS profile exits 2 naming the file (it used to exit 1 in some and 2
# in others: dds::DdsInputError, docs/architecture.md "Configuration and errors"). About 30 s.
source "$(dirname "$0")/lib.sh"

scene="$source_dir/deploy/scenes/demo.yaml"
ptz="$source_dir/deploy/ptz/walk_side.yaml"

# program|arguments that would run it on the bus (the domain is refused first; nothing else may fail)
programs=(
  "camera_node|--source sim:$scene#cam0 --duration 1 --quiet"
  "estimator_node|--duration 1 --quiet"
  "estimator_node|calibrate capture --out $work/capture.jsonl --duration 1"
  "panoptes_console|--bind 127.0.0.1:0 --calibration-dir $work/calibration"
  "panoptes_record|--out $work/out.mcap --duration 1 --quiet"
  "panoptes_record|--command stop"
  "panoptes_replay|$work/missing.mcap"
  "panoptes_ctl|status --count 1"
  "panoptes_demo|--duration 2 --log-dir $work/demo"
  "panoptes_feature_flood|--duration 1"
  "panoptes_rogue|--duration 1"
  "panoptes_track_probe|--out $work/tracks.jsonl --duration 1"
  "panoptes_feature_probe|--out $work/features.jsonl --duration 1"
  "panoptes_ros2_probe|--out $work/ros2.jsonl --duration 1"
  "panoptes_client_probe|--out $work/client.jsonl --duration 1"
  "panoptes_cyclone_probe|--bodies rigid_a --duration 1"
  "sample_client|--timeout-s 1"
  "ptz_guide|--ptz $ptz --track-near 0,0,1 --duration 1"
  "lumipoint_board|--out $work/board.ppm --duration 1"
  "grab_objects|--duration 1"
  "bench_client|--duration 1"
  "bench_ros2_outputs|--seconds 1"
  "bench_latency|--duration 2"
)
# Link Fast DDS through the recording library (its CDR and topic types) but open no participant:
# they read and write MCAP files only.
no_participant=(bench_recorder panoptes_mcap_probe)

listed() {  # NAME: whether NAME is in the table or opens no participant
  local entry
  for entry in "${programs[@]}" "${no_participant[@]}"; do [ "${entry%%|*}" = "$1" ] && return 0; done
  return 1
}

# Every executable in build/bin that links Fast DDS or the client library is in the table.
for program in "$bin"/*; do
  name=$(basename "$program")
  [ -x "$program" ] && [ -f "$program" ] || continue
  case "$name" in *_tests) continue ;; esac
  libraries=$(ldd "$program" 2>/dev/null)  # not piped into grep -q: with pipefail, ldd's SIGPIPE fails it
  grep -qE 'libfastrtps|libpanoptes_client|libddsc' <<<"$libraries" || continue
  listed "$name" && pass "$name is checked" || fail "$name opens DDS but is not in test_bad_domain.sh's table"
done

# expect_refused SETTING MESSAGE NAME ARGS...: NAME run with the environment SETTING (VAR=value)
# exits 2 with exactly one stderr line that contains MESSAGE.
expect_refused() {
  local setting="$1" message="$2" name="$3"
  shift 3
  expect_exit 2 "$setting $name ${*:1:2}" -- env "$setting" timeout 30 "$bin/$name" "$@"
  if [ "$(grep -cF -- "$message" "$work/last.err")" -eq 1 ]; then
    pass "$name says '$message' once"
  else
    fail "$name: stderr lacks one line '$message'"
    cat "$work/last.err"
  fi
}

for entry in "${programs[@]}"; do
  name="${entry%%|*}"
  read -r -a args <<<"${entry#*|}"
  if [ ! -x "$bin/$name" ]; then
    echo "SKIP: $name is not built"
    continue
  fi
  for bad in abc 300; do
    expect_refused "PANOPTES_DOMAIN=$bad" "PANOPTES_DOMAIN=$bad: not a DDS domain id (an integer 0..232)" \
      "$name" "${args[@]}"
  done
done

# A missing profile file, named by the variable every program reads.
missing_profile="$work/missing-profile.xml"
# Cyclone DDS: no Fast DDS profile to load. bench_latency: its --dds-profile (default the source
# tree's loopback.xml, checked by its parser) for every process, so that its runs compare.
no_fast_dds_profile=(panoptes_cyclone_probe bench_latency)
for entry in "${programs[@]}"; do
  name="${entry%%|*}"
  read -r -a args <<<"${entry#*|}"
  [ -x "$bin/$name" ] || continue
  [[ " ${no_fast_dds_profile[*]} " == *" $name "* ]] && continue
  expect_refused "PANOPTES_DDS_PROFILE=$missing_profile" "PANOPTES_DDS_PROFILE=$missing_profile: no such file" \
    "$name" "${args[@]}"
done

# The client programs take --domain: only 0..232; a negative id is an error (the environment is
# read when the option is absent), not a way to ask for $PANOPTES_DOMAIN.
for name in sample_client lumipoint_board grab_objects panoptes_client_probe; do
  [ -x "$bin/$name" ] || continue
  for bad in -1 300; do
    args=(--domain "$bad")
    case "$name" in
      lumipoint_board) args+=(--out "$work/board.ppm") ;;
      panoptes_client_probe) args+=(--out "$work/client.jsonl") ;;
    esac
    expect_exit 2 "$name --domain $bad" -- timeout 30 "$bin/$name" "${args[@]}"
    expect_stderr_contains "--domain" "$name --domain $bad names the option"
  done
done

# Every program and tool that opens DDS takes --domain N (issue 34 item 10): checked like
# $PANOPTES_DOMAIN (a typo exits 2 naming --domain, never domain 0, even with a good variable set),
# and --help shows it with its default.
flag_programs=(camera_node estimator_node panoptes_console panoptes_record panoptes_replay panoptes_ctl panoptes_demo)
for entry in "${programs[@]}"; do
  name="${entry%%|*}"
  [[ " ${flag_programs[*]} " == *" $name "* ]] || continue
  [ -x "$bin/$name" ] || continue
  read -r -a args <<<"${entry#*|}"
  for bad in 8x9 300 -1; do
    expect_refused "PANOPTES_DOMAIN=89" "--domain=$bad: not a DDS domain id (an integer 0..232)" \
      "$name" "${args[@]}" --domain "$bad"
  done
done
for name in "${flag_programs[@]}"; do
  [ -x "$bin/$name" ] || continue
  expect_exit 0 "$name --help" -- "$bin/$name" --help
  grep -qF -- '--domain' "$work/last.out" && grep -qF 'default: $PANOPTES_DOMAIN, else 0' "$work/last.out" \
    && pass "$name --help shows --domain and its default" || fail "$name --help lacks --domain with its default"
done
expect_exit 0 "estimator_node calibrate capture --help" -- "$bin/estimator_node" calibrate capture --help
grep -qF -- '--domain' "$work/last.out" && pass "calibrate capture --help shows --domain" \
  || fail "calibrate capture --help lacks --domain"

# The Python client raises panoptes.ClientError with the same message.
python=$(cat "$build_dir/python/INTERPRETER" 2>/dev/null)
if [ -n "$python" ] && [ -d "$build_dir/python/panoptes" ]; then
  for bad in abc 300; do
    expect_exit 0 "Python: PANOPTES_DOMAIN=$bad raises ClientError naming it" -- \
      env PANOPTES_DOMAIN="$bad" PYTHONPATH="$build_dir/python" "$python" -c "
import panoptes
try:
    panoptes.Client()
except panoptes.ClientError as error:
    assert str(error) == 'PANOPTES_DOMAIN=$bad: not a DDS domain id (an integer 0..232)', str(error)
else:
    raise SystemExit('no ClientError')"
  done
else
  echo "SKIP: the Python bindings are not built"
fi

finish
