#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job: builds if needed, then runs the simulated multi-camera demo over DDS (loopback),
# with the operator console (docs/console.md) serving on 127.0.0.1:${PANOPTES_CONSOLE_PORT:-8080};
# its URL, with the access token, is the first line printed. --no-console leaves it out.
# Other arguments go to panoptes_demo (see build/bin/panoptes_demo --help), e.g. --duration 60.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
console=1
demo_args=()
for argument in "$@"; do
  if [ "$argument" = "--no-console" ]; then console=0; else demo_args+=("$argument"); fi
done
bash "$root/deploy/build.sh"
bin="$root/${PANOPTES_BUILD_DIR:-build}/bin"
console_pid=""
url_file=""
cleanup() {
  if [ -n "$console_pid" ]; then kill -INT "$console_pid" 2>/dev/null || true; wait "$console_pid" 2>/dev/null || true; fi
  [ -n "$url_file" ] && rm -f "$url_file"
  bash "$root/deploy/dds-shm-clean.sh"
}
trap cleanup EXIT
if [ "$console" -eq 1 ]; then
  url_file="$(mktemp /tmp/panoptes-console-url-XXXXXX)"
  : >"$url_file"
  "$bin/panoptes_console" --bind "127.0.0.1:${PANOPTES_CONSOLE_PORT:-8080}" --url-file "$url_file" \
    >/tmp/panoptes-console.log 2>&1 &
  console_pid=$!
  for _ in $(seq 50); do [ -s "$url_file" ] && break; kill -0 "$console_pid" 2>/dev/null || break; sleep 0.1; done
  if [ -s "$url_file" ]; then
    echo "Console: $(cat "$url_file")   (open it in a browser; --no-console to leave it out)"
  else
    echo "Console: did not start ($(tail -1 /tmp/panoptes-console.log)); the demo runs without it"
    console_pid=""
  fi
fi
"$bin/panoptes_demo" "${demo_args[@]}"
