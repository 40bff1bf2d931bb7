#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The Python package `panoptes` without an estimator (issue 15 items 2 and 5, docs/clients.md
# "Python"): on an empty domain the client returns None within the timeout and the examples
# (log_poses_csv.py, plot_body.py) exit 1 saying so; a bad argument is named; `cmake --install` gives a
# package that imports from <prefix>/lib/python3/dist-packages and finds the installed library and
# profile. The package live (its client beside the C++ one on the clients scene, the estimator
# killed and restarted; the examples writing the live poses to CSV and a PNG) is in
# integration.test_client (stop 67: one live run for both languages).
source "$(dirname "$0")/lib.sh"
python=$(cat "$build_dir/python/INTERPRETER" 2>/dev/null)
[ -n "$python" ] && [ -f "$build_dir/python/panoptes/__init__.py" ] || { fail "the Python package is not built ($build_dir/python)"; finish; }
export PYTHONPATH="$build_dir/python"

# --- an empty domain ----------------------------------------------------------------------------
expect_exit 0 "wait_for_frame on an empty domain returns None within the timeout" -- "$python" -c "
import re, time, panoptes
with panoptes.Client(domain=$empty_domain) as c:
    start = time.monotonic()
    frame = c.wait_for_frame(1.0)
    elapsed = time.monotonic() - start
    print(c.status_text())
    assert frame is None and 0.99 <= elapsed < 2.0, (frame, elapsed)
    assert re.search(r'no data for [0-9]+[.][0-9] s', c.status_text()), c.status_text()"
start=$(date +%s%N)
expect_exit 1 "log_poses_csv.py on an empty domain exits non-zero" -- "$python" "$source_dir/examples/log_poses_csv.py" \
  --domain "$empty_domain" --timeout 2 --out "$work/empty.csv"
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
expect_stderr_matches "no data for [0-9]+\\.[0-9] s" "it says 'no data for N s'"
expect_stderr_contains "is estimator_node running?" "it says what to check"
[ "$elapsed_ms" -lt 6000 ] && pass "it gave up within the timeout ($elapsed_ms ms for --timeout 2, interpreter start included)" ||
  fail "it took $elapsed_ms ms for --timeout 2"
expect_exit 2 "log_poses_csv.py rejects a bad argument" -- "$python" "$source_dir/examples/log_poses_csv.py" --duration soon
expect_stderr_contains "--duration" "the error names the argument"
expect_exit 1 "plot_body.py on an empty domain exits non-zero" -- "$python" "$source_dir/examples/plot_body.py" \
  --domain "$empty_domain" --timeout 1 --duration 2 --save "$work/empty.png"
expect_stderr_matches "no data for [0-9]+\\.[0-9] s" "it says 'no data for N s'"

# --- installed: cmake --install puts the package in <prefix>/lib/python3/dist-packages --------------
prefix="$work/prefix"
expect_exit 0 "cmake --install into a prefix" -- cmake --install "$build_dir" --prefix "$prefix"
expect_exit 0 "the installed package imports and finds libpanoptes_client.so and the installed profile" -- \
  env -u PANOPTES_DDS_PROFILE PYTHONPATH="$prefix/lib/python3/dist-packages" "$python" -c "
import panoptes, sys
assert panoptes.__file__.startswith('$prefix/lib/python3/dist-packages/panoptes/'), panoptes.__file__
with panoptes.Client(domain=$empty_domain) as c:
    assert c.profile_file == '$prefix/share/panoptes/dds/loopback.xml', c.profile_file
    assert c.wait_for_frame(0.2) is None"
# ldd's whole output first: grep -q would close the pipe early (SIGPIPE under pipefail).
libraries=$(ldd "$prefix"/lib/python3/dist-packages/panoptes/_panoptes*.so)
grep -q "libpanoptes_client.so.* => $prefix/lib/python3/dist-packages/panoptes/\.\./\.\./\.\./libpanoptes_client" <<<"$libraries" &&
  pass "the installed module loads the installed libpanoptes_client.so (RUNPATH \$ORIGIN)" ||
  { fail "the installed module does not find the installed library"; echo "$libraries"; }
rm -rf "$prefix"

finish
