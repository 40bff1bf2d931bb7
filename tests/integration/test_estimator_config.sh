#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# estimator_node --config / --print-config (issue 14; docs/estimator.md, "Configuration"): the
# printed defaults reproduce the default offline run bit for bit, the printed file loads again,
# explicit flags override the file, and a bad file names the file and key and exits 2.
source "$(dirname "$0")/lib.sh"
scene="$source_dir/deploy/scenes/bodies.yaml"

expect_exit 0 "simulate the two-body scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim" --duration 3
offline() {  # offline OUT-PREFIX [extra estimator_node arguments...]
  local prefix="$1"
  shift
  "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" --bodies "$work/sim/bodies.yaml" \
    --in-features "$work"/sim/c*.jsonl --no-dds --out-tracks "$work/$prefix.tracks.jsonl" \
    --out-poses "$work/$prefix.poses.jsonl" --quiet "$@" >"$work/$prefix.out" 2>"$work/$prefix.err"
}

# --- the printed defaults reproduce the default run ---------------------------------------------
expect_exit 0 "--print-config" -- "$bin/estimator_node" --print-config
cp "$work/last.out" "$work/c.yaml"
grep -q '^tracker:' "$work/c.yaml" && grep -q '^  process_noise: 50' "$work/c.yaml" && grep -q 'led_marker:' "$work/c.yaml" &&
  pass "the printed configuration has the tracker, bodies and LED-marker settings" || fail "printed configuration incomplete"
# docs/estimator.md lists every key "as --print-config prints it": the block is the printed file.
awk '/^Every key with its default and meaning/ { on = 1; next } on && /^```yaml$/ { inside = 1; next }
  inside && /^```$/ { exit } inside { print }' "$source_dir/docs/estimator.md" >"$work/doc_config.yaml"
diff -u "$work/doc_config.yaml" "$work/c.yaml" >"$work/doc_config.diff" &&
  pass "docs/estimator.md's configuration block is what --print-config prints" ||
  fail "docs/estimator.md's configuration block differs from --print-config (regenerate it): $(head -c 600 "$work/doc_config.diff")"
offline default && pass "default offline run" || fail "default offline run: exit $?"
offline config --config "$work/c.yaml" && pass "offline run with the printed configuration" || fail "run with --config: exit $?"
[ -s "$work/default.tracks.jsonl" ] && [ -s "$work/default.poses.jsonl" ] && pass "the runs wrote tracks and poses" ||
  fail "no tracks or poses written"
cmp -s "$work/default.tracks.jsonl" "$work/config.tracks.jsonl" && pass "tracks identical with --config (printed defaults)" ||
  fail "tracks differ with --config"
cmp -s "$work/default.poses.jsonl" "$work/config.poses.jsonl" && pass "poses identical with --config (printed defaults)" ||
  fail "poses differ with --config"
cmp -s "$work/default.err" "$work/config.err" && pass "the same log with --config" || fail "logs differ with --config"
expect_exit 0 "--print-config of a loaded configuration" -- "$bin/estimator_node" --config "$work/c.yaml" --print-config
cmp -s "$work/c.yaml" "$work/last.out" && pass "the printed configuration loads back unchanged" ||
  fail "printing a loaded configuration changed it"

# --- the file takes effect; explicit flags win over it ------------------------------------------
sed 's/^\(  process_noise:\) 50/\1 400/; s/^\(  confirm_cameras:\) 3/\1 4/' "$work/c.yaml" >"$work/tuned.yaml"
expect_exit 0 "--print-config with a tuned file" -- "$bin/estimator_node" --config "$work/tuned.yaml" --print-config
grep -q '^  process_noise: 400' "$work/last.out" && grep -q '^  confirm_cameras: 4' "$work/last.out" &&
  pass "the file's values are in effect" || fail "the file's values are not in effect"
expect_exit 0 "--print-config with a tuned file and a flag" -- "$bin/estimator_node" --config "$work/tuned.yaml" \
  --confirm-cameras 2 --print-config
grep -q '^  process_noise: 400' "$work/last.out" && grep -q '^  confirm_cameras: 2' "$work/last.out" &&
  pass "an explicit flag overrides the file, the rest of the file stays" || fail "flag precedence wrong"
offline tuned --config "$work/tuned.yaml" && pass "offline run with a tuned file" || fail "tuned run: exit $?"
cmp -s "$work/default.tracks.jsonl" "$work/tuned.tracks.jsonl" && fail "a tuned file left the tracks unchanged" ||
  pass "a tuned file changes the run"

# --- bad files ----------------------------------------------------------------------------------
printf 'tracker:\n  init:\n    windw_ns: 30000000\n' >"$work/unknown.yaml"
expect_exit 2 "unknown key" -- "$bin/estimator_node" --config "$work/unknown.yaml" --print-config
expect_stderr_contains "unknown.yaml: tracker.init.windw_ns: unknown key" "the file and key path are named"
[ "$(wc -l <"$work/last.err")" -eq 1 ] && pass "one line for an unknown key" || fail "unknown key gave $(wc -l <"$work/last.err") lines"
printf 'tracker:\n  bodies:\n    gate_chi2: -3\n' >"$work/range.yaml"
expect_exit 2 "out-of-range value" -- "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --in-features "$work"/sim/c*.jsonl --no-dds --config "$work/range.yaml"
expect_stderr_contains "range.yaml: tracker.bodies.gate_chi2: must be a finite number > 0" "the file, key and range are named"
[ "$(wc -l <"$work/last.err")" -eq 1 ] && pass "one line for an out-of-range value" || fail "out of range gave $(wc -l <"$work/last.err") lines"
expect_exit 2 "missing configuration file" -- "$bin/estimator_node" --config "$work/none.yaml" --print-config
expect_stderr_contains "none.yaml" "the missing file is named"
# The ROS 2 options (docs/ros2.md, "Options"): flags and keys round-trip; bad values exit 2 naming them.
expect_exit 0 "ROS 2 tf rate and namespace flags" -- "$bin/estimator_node" --ros2-tf-rate-hz 50 \
  --ros2-namespace /lab1 --print-config
grep -q 'tf_rate_hz: 50' "$work/last.out" && grep -q 'namespace: "/lab1"' "$work/last.out" &&
  pass "--print-config shows ros2.tf_rate_hz and ros2.namespace" || fail "ros2 tf_rate_hz/namespace not printed"
expect_exit 0 "ROS 2 defaults" -- "$bin/estimator_node" --print-config
grep -q 'tf_rate_hz: 120' "$work/last.out" && grep -q 'namespace: ""' "$work/last.out" &&
  pass "default ros2.tf_rate_hz 120, no namespace" || fail "ros2 defaults"
expect_exit 2 "an out-of-range --ros2-tf-rate-hz" -- "$bin/estimator_node" --ros2-tf-rate-hz 20000 --print-config
expect_stderr_contains "--ros2-tf-rate-hz" "the error names --ros2-tf-rate-hz"
expect_exit 2 "a non-numeric --ros2-tf-rate-hz" -- "$bin/estimator_node" --ros2-tf-rate-hz fast --print-config
expect_stderr_contains "--ros2-tf-rate-hz" "the error names --ros2-tf-rate-hz"
expect_exit 2 "an invalid --ros2-namespace" -- "$bin/estimator_node" --ros2-namespace /lab-1 --print-config
expect_stderr_contains "--ros2-namespace" "the error names --ros2-namespace"
expect_stderr_contains "ROS 2 names hold only" "and says why"
printf 'ros2:\n  namespace: "/lab1/"\n' >"$work/bad_ns.yaml"
expect_exit 2 "an invalid ros2.namespace" -- "$bin/estimator_node" --config "$work/bad_ns.yaml" --print-config
expect_stderr_contains "ros2.namespace" "the error names ros2.namespace"
printf 'ros2:\n  tf_rate_hz: -5\n' >"$work/bad_tf.yaml"
expect_exit 2 "a negative ros2.tf_rate_hz" -- "$bin/estimator_node" --config "$work/bad_tf.yaml" --print-config
expect_stderr_contains "ros2.tf_rate_hz" "the error names ros2.tf_rate_hz"
expect_exit 2 "an unknown ROS 2 option" -- "$bin/estimator_node" --ros2-tf-rate 50 --print-config
expect_stderr_contains "--ros2-tf-rate" "the error names the unknown option"

expect_exit 0 "--help" -- "$bin/estimator_node" --help
grep -q -- '--process-noise.*50' "$work/last.out" && pass "--help shows defaults" || fail "--help lacks defaults"

finish
