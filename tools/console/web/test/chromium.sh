#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Debian's chromium for the browser tests, without the right to raise its own priority. Run as root
# (CI, a container), chromium sets its GPU, compositor and browser threads to nice -8 and the
# page's renderer to 0: beside the live tests' camera_nodes and estimator_node (nice 0) on 2 cores,
# its software WebGL then took the CPU they needed, and eight cameras' frames stalled for 0.5 s
# (test_live_labels, issue 37). Without CAP_SYS_NICE it keeps the nice value it was started with.
if [ "$(id -u)" = 0 ] && command -v setpriv >/dev/null 2>&1; then
  exec setpriv --bounding-set=-sys_nice --inh-caps=-sys_nice /usr/bin/chromium "$@"
fi
exec /usr/bin/chromium "$@"
