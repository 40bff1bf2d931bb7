#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Removes the Fast DDS shared-memory files that no live participant owns and no process maps:
# segments (/dev/shm/fastrtps_<id>) and ports (fastrtps_port<N>, with sem.fastrtps_port<N>_mutex)
# left by processes that were killed (tests kill estimator_node with -9), so that they do not pile
# up. It is safe while other Panoptes processes run, e.g. tests running in parallel (docs/testing.md,
# "Shared memory"): a file is removed only if
#   - it is older than PANOPTES_SHM_CLEAN_MIN_AGE_S seconds (default 10): a participant creates its
#     files, then locks and maps them; a file seen in between would look abandoned;
#   - its lock file (<file>_el or _sl), if any, is not locked: a live owner holds that lock;
#   - no process maps it: writers keep a killed reader's port mapped, and a new segment under that
#     name would cut the next reader off from them (docs/protocol.md, "Restarting after a crash").
# `fastdds shm clean` (Fast DDS 2.9) checks the lock only, so it removes such ports, and files a
# starting participant has created but not yet locked; this script replaces it.
set -uo pipefail
shm="${PANOPTES_SHM_DIR:-/dev/shm}"
min_age_s="${PANOPTES_SHM_CLEAN_MIN_AGE_S:-10}"
now=$(date +%s)
# One read of every process's maps and one stat of every file: the test suite runs this at the end
# of every integration test, with hundreds of files present while other tests run; a grep and a stat
# per file took 2.4 s at the end of test_console (4.3 s for 460 files), now 0.1 s (docs/testing.md).
declare -A in_use=() mtime=()
while read -r file; do in_use[$file]=1; done < <(cat /proc/[0-9]*/maps 2>/dev/null | grep -o "$shm/fastrtps_[^ ]*" | sort -u)
files=("$shm"/fastrtps_*)
[ -e "${files[0]}" ] || exit 0
while read -r modified file; do mtime[$file]=$modified; done < <(stat -c '%Y %n' -- "${files[@]}" 2>/dev/null)

old_enough() {  # FILE...: every one that exists is older than min_age_s
  local file
  for file in "$@"; do
    [ -n "${mtime[$file]+set}" ] || continue
    [ $((now - mtime[$file])) -ge "$min_age_s" ] || return 1
  done
  return 0
}

unlocked() {  # LOCK_FILE: not locked by any process (a missing file is not locked)
  [ ! -e "$1" ] || flock --nonblock --exclusive "$1" true 2>/dev/null
}

for file in "${files[@]}"; do
  [ -e "$file" ] || continue
  case "$file" in *_el | *_sl) continue ;; esac
  [ -n "${in_use[$file]+set}" ] && continue
  old_enough "$file" "${file}_el" "${file}_sl" || continue
  unlocked "${file}_el" && unlocked "${file}_sl" || continue
  rm -f "$file" "${file}_el" "${file}_sl" "$shm/sem.${file##*/}_mutex"
done
# Lock files whose segment or port is gone.
for lock in "$shm"/fastrtps_*_el "$shm"/fastrtps_*_sl; do
  [ -e "$lock" ] && [ ! -e "${lock%_??}" ] || continue
  old_enough "$lock" && unlocked "$lock" && rm -f "$lock"
done
exit 0
