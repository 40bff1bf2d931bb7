#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The Debian package (CPack DEB, cmake/PanoptesInstall.cmake): builds it from this build tree,
# checks its contents (programs, DDS profiles, systemd units whose paths point at installed files,
# examples), installs it with dpkg -i, starts the installed units against the simulator as
# docs/deployment.md says ("Trying the units without cameras"), checks tracking, and removes it
# with dpkg --purge, leaving nothing behind. systemd is used when it runs as PID 1; otherwise (a
# container, CI) each unit's ExecStart runs directly with its EnvironmentFile, as systemd would.
# Root only; skips (77) when not root, without dpkg/cpack, or when panoptes or /etc/panoptes exist.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/lib.sh"
set -eE
# A command failing outside a check (also inside a function: -E) is a failure too, and keeps $work.
trap 'failures=$((failures + 1)); echo "FAIL: unexpected error at line $LINENO"' ERR
skip() { echo "SKIP: $*"; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "not root (dpkg -i installs into this machine)"
command -v dpkg >/dev/null && command -v cpack >/dev/null || skip "no dpkg or cpack"
dpkg -s panoptes >/dev/null 2>&1 && skip "a panoptes package is already installed; not touching it"
[ -e /etc/panoptes ] && skip "/etc/panoptes exists; not touching it"
installed=0
unit_pids=()
package_cleanup() {
  for pid in "${unit_pids[@]}"; do kill -KILL "$pid" 2>/dev/null || true; done
  if [ "$installed" -eq 1 ]; then dpkg --purge panoptes >/dev/null 2>&1 || true; fi
  rm -rf /etc/panoptes
}
trap 'package_cleanup; cleanup' EXIT
trap 'exit 143' TERM INT

# --- build and inspect --------------------------------------------------------------------------
(cd "$build_dir" && cpack -G DEB -B "$work/pkg" >"$work/cpack.log" 2>&1) || { fail "cpack"; cat "$work/cpack.log"; finish; }
deb=$(ls "$work"/pkg/panoptes_*.deb)
pass "built $(basename "$deb") ($(du -k "$deb" | cut -f1) kB)"
dpkg-deb -c "$deb" | awk '{print $6}' | sed 's#^\./#/#' >"$work/contents.txt"
for path in /usr/bin/camera_node /usr/bin/estimator_node /usr/bin/panoptes_ctl /usr/bin/panoptes_sim \
  /usr/share/panoptes/dds/loopback.xml /usr/share/panoptes/dds/lan.xml /usr/share/panoptes/dds/shm.xml \
  /usr/share/panoptes/dds/discovery_client.xml /lib/systemd/system/camera_node@.service \
  /lib/systemd/system/estimator_node.service /lib/systemd/system/panoptes-discovery.service \
  /usr/share/panoptes/scenes/demo.yaml /usr/share/panoptes/examples/lab4/camera_node/cam0.env \
  /usr/share/panoptes/examples/sim/estimator_node.env /usr/share/doc/panoptes/deployment.md \
  /usr/lib/libpanoptes_client.so /usr/include/panoptes/client/client.h /usr/lib/cmake/Panoptes/PanoptesConfig.cmake \
  /usr/lib/pkgconfig/panoptes-client.pc /usr/share/doc/panoptes/clients.md; do
  grep -qx "$path" "$work/contents.txt" && pass "package holds $path" || fail "package lacks $path"
done
dpkg-deb -f "$deb" Depends | grep -q libfastrtps && pass "depends on the Fast DDS library" || fail "Depends: $(dpkg-deb -f "$deb" Depends)"

# --- install --------------------------------------------------------------------------------------
if dpkg -i "$deb" >"$work/dpkg.log" 2>&1; then installed=1; pass "dpkg -i"; else fail "dpkg -i"; cat "$work/dpkg.log"; finish; fi
# The client library is known to the dynamic linker and to pkg-config (docs/clients.md).
# Into a file first: ldconfig -p prints ~100 kB, and with pipefail grep -q's early exit would
# fail the pipeline on SIGPIPE whenever the library is listed before the last pipe buffer.
ldconfig -p >"$work/ldconfig.txt"
grep -q "libpanoptes_client.so" "$work/ldconfig.txt" && pass "ldconfig knows libpanoptes_client" || fail "libpanoptes_client not in the ldconfig cache"
[ "$(pkg-config --modversion panoptes-client 2>/dev/null)" = "$(dpkg-deb -f "$deb" Version)" ] &&
  pass "pkg-config finds panoptes-client $(pkg-config --modversion panoptes-client)" || fail "pkg-config panoptes-client"
# Every absolute path a unit names (programs, its settings' examples) exists once installed.
for unit in camera_node@.service estimator_node.service panoptes-discovery.service; do
  file=/lib/systemd/system/$unit
  for path in $(grep -E '^(ExecStart|ExecStartPre)=' "$file" | sed -E 's/^[A-Za-z]+=-?//' | awk '{print $1}'); do
    case "$path" in
      /usr/bin/fast*) ;;  # fastdds-tools: recommended, not required
      *) [ -x "$path" ] && pass "$unit runs $path" || fail "$unit names $path, which is not installed" ;;
    esac
  done
done
# systemd's own check of the installed units (syntax, directives, executables), which works without
# systemd running as PID 1.
if command -v systemd-analyze >/dev/null; then
  for unit in camera_node@cam0.service estimator_node.service panoptes-discovery.service; do
    # Unknown or invalid settings are only warnings ("..., ignoring.") with exit 0: count them too.
    if systemd-analyze verify --man=no "$unit" >"$work/verify.log" 2>&1 && ! grep -qi "ignoring" "$work/verify.log"; then
      pass "systemd-analyze verify $unit"
    else
      case "$unit" in
        # fastdds-tools is recommended, not required: its program may be missing.
        panoptes-discovery.service) grep -v "fast-discovery-server\|fastdds" "$work/verify.log" | grep -q . &&
          { fail "systemd-analyze verify $unit"; cat "$work/verify.log"; } || pass "systemd-analyze verify $unit (fastdds-tools absent)" ;;
        *) fail "systemd-analyze verify $unit"; cat "$work/verify.log" ;;
      esac
    fi
  done
fi
grep -q "EnvironmentFile=/etc/panoptes/camera_node/%i.env" /lib/systemd/system/camera_node@.service &&
  pass "camera_node@.service reads /etc/panoptes/camera_node/<camera>.env" || fail "camera unit settings path"
for env in /usr/share/panoptes/examples/*/camera_node/*.env /usr/share/panoptes/examples/*/*.env; do
  for value in $(grep -oE '/usr/share/panoptes/[^ #"]*' "$env" | sed 's/#.*//' || true); do
    [ -e "$value" ] || fail "$(basename "$env") names $value, which is not installed"
  done
done
pass "the example settings name installed files only"

# --- start the installed units against the simulator ------------------------------------------------
mkdir -p /etc/panoptes/camera_node
cp /usr/share/panoptes/examples/sim/estimator_node.env /etc/panoptes/
epoch=$((($(date +%s) + 3) * 1000000000))
for i in 0 1 2 3; do
  # The guide: the four simulated cameras share a scene epoch.
  sed "s/^PANOPTES_CAMERA_ARGS=.*/PANOPTES_CAMERA_ARGS=\"--sim-epoch-ns $epoch\"/" \
    /usr/share/panoptes/examples/sim/camera_node/cam$i.env >/etc/panoptes/camera_node/cam$i.env
done
# run_unit UNIT INSTANCE LOG: the unit's ExecStart with its EnvironmentFile, as systemd runs it.
run_unit() {
  local file="/lib/systemd/system/$1" instance="$2" log="$3" envfile command
  envfile=$(sed -n 's/^EnvironmentFile=-\{0,1\}//p' "$file" | sed "s/%i/$instance/g")
  command=$(sed -n 's/^ExecStart=//p' "$file" | sed "s/%i/$instance/g")
  (set -a; source "$envfile"; set +a; eval "exec $command") >"$log" 2>&1 &
  unit_pids+=("$!")
}
if [ -d /run/systemd/system ] && [ "$(cat /proc/1/comm)" = systemd ]; then
  echo "systemd is PID 1: starting the units with systemctl"
  systemctl start estimator_node.service camera_node@cam{0,1,2,3}.service
  sleep 7  # 4-5 s of frames after the epoch (7-8 s until stop 79): utilisation and 3 tracks are judged
  systemctl stop camera_node@cam{0,1,2,3}.service estimator_node.service
  journalctl -u estimator_node.service --no-pager >"$work/estimator.log"
else
  echo "systemd is not PID 1 ($(cat /proc/1/comm)): running each unit's ExecStart with its EnvironmentFile"
  run_unit estimator_node.service "" "$work/estimator.log"
  estimator=${unit_pids[-1]}
  for i in 0 1 2 3; do run_unit camera_node@.service "cam$i" "$work/cam$i.log"; done
  sleep 7  # 4-5 s of frames after the epoch (7-8 s until stop 79): utilisation and 3 tracks are judged
  for pid in "${unit_pids[@]:1}"; do kill -INT "$pid" 2>/dev/null || true; done
  sleep 1
  kill -INT "$estimator" 2>/dev/null || true
  for pid in "${unit_pids[@]}"; do timeout 10 tail -s 0.05 --pid="$pid" -f /dev/null || true; done
fi
grep -q "DDS profile /usr/share/panoptes/dds/loopback.xml" "$work/estimator.log" &&
  pass "the installed estimator uses the installed loopback profile" || fail "estimator profile: $(head -3 "$work/estimator.log")"
cameras=$(grep -c "camera cam[0-3]: .*utilisation 1.0000\|camera cam[0-3]: .*utilisation 0.9[5-9]" "$work/estimator.log" || true)
[ "$cameras" -eq 4 ] && pass "the installed estimator used >= 95% of the frames of all 4 installed camera nodes" ||
  { fail "estimator usage ($cameras cameras)"; tail -8 "$work/estimator.log"; }
confirmed=$(grep -o "confirmed [0-9]*" "$work/estimator.log" | tail -1 | awk '{print $2}' || true)
[ "${confirmed:-0}" -ge 3 ] && pass "$confirmed tracks confirmed (the scene has 3 markers)" ||
  fail "tracks confirmed: ${confirmed:-none}"

# --- remove ---------------------------------------------------------------------------------------
rm -rf /etc/panoptes
if dpkg --purge panoptes >"$work/purge.log" 2>&1; then installed=0; pass "dpkg --purge"; else fail "dpkg --purge"; cat "$work/purge.log"; fi
left=""
for path in $(grep -v '/$' "$work/contents.txt"); do [ -e "$path" ] && left="$left $path"; done
[ -z "$left" ] && [ ! -e /usr/share/panoptes ] && pass "nothing of the package is left" || fail "left behind:$left"
finish
