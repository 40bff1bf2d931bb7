#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Removes Fast DDS shared-memory files that no process maps any more. `fastdds shm clean` (Fast DDS
# 2.9) can leave the port files (/dev/shm/fastrtps_port<N> and their sem.*_mutex) of processes that
# were killed (tests kill estimator_node with -9), so they pile up; it has also been seen to remove
# a killed process's port that writers still mapped (Panoptes processes keep off such a port:
# docs/protocol.md, "Restarting after a crash"). A file some process still maps (an open
# participant, e.g. another test running in parallel) is left alone by the loop below.
fastdds shm clean >/dev/null 2>&1 || true
in_use="$(cat /proc/[0-9]*/maps 2>/dev/null | grep -o '/dev/shm/fastrtps_[^ ]*' | sort -u)"
for file in /dev/shm/fastrtps_port*; do
  [ -e "$file" ] || continue
  case "$file" in *_el) continue ;; esac
  if ! grep -qxF "$file" <<<"$in_use"; then
    rm -f "$file" "/dev/shm/sem.$(basename "$file")_mutex"
  fi
done
exit 0
