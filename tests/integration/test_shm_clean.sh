#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# deploy/dds-shm-clean.sh (docs/testing.md, "Shared memory") on a directory of its own
# (PANOPTES_SHM_DIR), as every integration test runs it on /dev/shm at its end while other tests run:
# it removes what a killed participant left (an old segment or port with its lock file and port
# mutex, an old lock file whose segment is gone) and keeps what may be in use (a fresh file, one
# whose lock a process holds, one a process maps). Then its time on 1000 fresh files, printed.
source "$(dirname "$0")/lib.sh"
shm="$work/shm"
mkdir -p "$shm"
old() { touch -d '1 minute ago' "$@"; }

# Left by killed participants: removed.
touch "$shm/fastrtps_00000000000000a1" "$shm/fastrtps_00000000000000a1_el"
touch "$shm/fastrtps_port7411" "$shm/fastrtps_port7411_el" "$shm/sem.fastrtps_port7411_mutex"
touch "$shm/fastrtps_00000000000000a2_el"  # its segment is gone
old "$shm"/*
# Kept: fresh (a participant that has not locked its files yet), locked, mapped.
touch "$shm/fastrtps_00000000000000b1" "$shm/fastrtps_00000000000000b1_el"
touch "$shm/fastrtps_00000000000000b2" "$shm/fastrtps_00000000000000b2_el" "$shm/fastrtps_00000000000000b3_el"
truncate -s 4096 "$shm/fastrtps_port7413"
old "$shm/fastrtps_00000000000000b2" "$shm/fastrtps_00000000000000b2_el" "$shm/fastrtps_00000000000000b3_el" \
  "$shm/fastrtps_port7413"
# One process holds the two locks (as a live participant holds its lock file) and maps the port.
python3 -c 'import fcntl, mmap, signal, sys, time
signal.signal(signal.SIGINT, lambda *_: sys.exit(0))  # a background job of a script ignores it
locks = [open(p, "r+b") for p in sys.argv[1:3]]
for f in locks: fcntl.flock(f, fcntl.LOCK_EX)
port = open(sys.argv[3], "r+b"); mapped = mmap.mmap(port.fileno(), 4096)
print("holding", flush=True); time.sleep(60)' \
  "$shm/fastrtps_00000000000000b2_el" "$shm/fastrtps_00000000000000b3_el" "$shm/fastrtps_port7413" \
  >"$work/holder.out" 2>&1 </dev/null &
pids+=("$!")
for _ in $(seq 100); do [ -s "$work/holder.out" ] && break; sleep 0.1; done
[ "$(cat "$work/holder.out")" = holding ] || { fail "the helper did not take the locks: $(cat "$work/holder.out")"; finish; }

PANOPTES_SHM_DIR="$shm" bash "$source_dir/deploy/dds-shm-clean.sh"
expect_gone() { [ ! -e "$shm/$1" ] && pass "removed $1 ($2)" || fail "kept $1 ($2)"; }
expect_kept() { [ -e "$shm/$1" ] && pass "kept $1 ($2)" || fail "removed $1 ($2)"; }
expect_gone fastrtps_00000000000000a1 "old, unlocked, unmapped segment"
expect_gone fastrtps_00000000000000a1_el "its lock file"
expect_gone fastrtps_port7411 "old, unlocked, unmapped port"
expect_gone fastrtps_port7411_el "its lock file"
expect_gone sem.fastrtps_port7411_mutex "its mutex"
expect_gone fastrtps_00000000000000a2_el "old lock file without its segment"
expect_kept fastrtps_00000000000000b1 "fresh segment"
expect_kept fastrtps_00000000000000b1_el "fresh lock file"
expect_kept fastrtps_00000000000000b2 "old segment whose lock is held"
expect_kept fastrtps_00000000000000b2_el "its held lock file"
expect_kept fastrtps_00000000000000b3_el "old lock file without a segment, held"
expect_kept fastrtps_port7413 "old port a process maps"

# Its time on a directory as full as /dev/shm gets during the suite (fresh files: all kept).
rm -rf "$shm" && mkdir -p "$shm"
for i in $(seq 1000 1499); do : >"$shm/fastrtps_0000000000000$i"; : >"$shm/fastrtps_0000000000000${i}_el"; done
start=$(date +%s%N)
PANOPTES_SHM_DIR="$shm" bash "$source_dir/deploy/dds-shm-clean.sh"
elapsed_ms=$((($(date +%s%N) - start) / 1000000))
kept=$(find "$shm" -type f | wc -l)
[ "$kept" -eq 1000 ] && pass "1000 fresh files kept, in $elapsed_ms ms" || fail "$kept of 1000 fresh files kept"
finish
