# SPDX-License-Identifier: Apache-2.0
# Simulated hosts for the multi-host tests: network namespaces joined by veth pairs to a bridge that
# itself lives in a namespace, so nothing is added to the root namespace and no packet can reach a
# real interface. Addresses 10.77.0.0/24 exist only inside these namespaces.
#
#   switch namespace  <prefix>sw : br0, and one veth end p<i> per host
#   host namespaces   <prefix>h<i>: lo, eth0 = 10.77.0.<10+i>/24, multicast routed to eth0
#
# Real hosts do not share memory: programs started with netns_spawn/netns_exec see a /dev/shm of
# their host only (a directory of the real /dev/shm bind-mounted in their own mount namespace), so
# Fast DDS's shared-memory transport works between processes on one host and never across hosts.
#
# Source after lib.sh. netns_cleanup kills what runs in the namespaces and deletes them; the test
# installs it on EXIT together with lib.sh's cleanup.
netns_prefix="pnp$$"
netns_names=()
netns_skip_code=77

# netns_reap_stale: deletes the namespaces (and their /dev/shm directories) of an earlier run that
# was killed before its EXIT trap could (SIGKILL, a machine or session cut off mid-test: seven were
# found left by a run killed at a session's end). A run's names start pnp<its shell's pid>; only
# those whose pid is gone are touched, so tests running in parallel keep theirs.
netns_reap_stale() {
  local ns owner pid
  for ns in $(ip netns list 2>/dev/null | awk '{print $1}' | grep -E '^pnp[0-9]+(sw|h[0-9]+|probe)$'); do
    owner="${ns#pnp}"
    owner="${owner%%[a-z]*}"
    [ "$owner" = "$$" ] && continue
    kill -0 "$owner" 2>/dev/null && continue
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$pid" 2>/dev/null || true; done
    ip netns del "$ns" 2>/dev/null && echo "removed namespace $ns left by a killed run"
    rm -rf "/dev/shm/pnp$owner"
  done
}

# netns_require: exits with the skip code, and a one-line reason, when namespaces cannot be used.
netns_require() {
  local reason=""
  if [ "$(id -u)" -ne 0 ]; then
    reason="not root (network namespaces need CAP_SYS_ADMIN)"
  elif ! command -v ip >/dev/null; then
    reason="no ip (iproute2)"
  else
    local probe="${netns_prefix}probe"
    if ! ip netns add "$probe" 2>/dev/null; then
      reason="ip netns add failed: no network namespace support"
    else
      if ! ip -n "$probe" link add br0 type bridge 2>/dev/null; then
        reason="the kernel has no bridge support"
      elif ! ip -n "$probe" link add v0 type veth peer name v1 2>/dev/null; then
        reason="the kernel has no veth support"
      fi
      ip netns del "$probe" 2>/dev/null
    fi
  fi
  if [ -n "$reason" ]; then
    echo "SKIP: $reason"
    exit "$netns_skip_code"
  fi
}

netns_shm_root="/dev/shm/${netns_prefix}"
netns_switch() { echo "${netns_prefix}sw"; }
netns_host() { echo "${netns_prefix}h$1"; }
netns_ip() { echo "10.77.0.$((10 + $1))"; }

# netns_create_lan N: a switch and hosts 1..N on it.
netns_create_lan() {
  local n="$1" sw i host
  sw="$(netns_switch)"
  ip netns add "$sw" && netns_names+=("$sw") || return 1
  ip -n "$sw" link set lo up
  ip -n "$sw" link add br0 type bridge mcast_snooping 0 || return 1
  ip -n "$sw" link set br0 up
  for i in $(seq 1 "$n"); do
    host="$(netns_host "$i")"
    ip netns add "$host" && netns_names+=("$host") || return 1
    ip -n "$host" link set lo up
    # Both ends are created inside namespaces: the root namespace never holds either.
    ip -n "$sw" link add "p$i" type veth peer name eth0 netns "$host" || return 1
    ip -n "$sw" link set "p$i" master br0
    ip -n "$sw" link set "p$i" up
    ip -n "$host" addr add "$(netns_ip "$i")/24" dev eth0
    ip -n "$host" link set eth0 up
    ip -n "$host" route add 224.0.0.0/4 dev eth0
    mkdir -p "$netns_shm_root/h$i"
  done
}

# netns_exec I COMMAND...: runs COMMAND on host I.
netns_exec() {
  local host
  host="$(netns_host "$1")"
  ip netns exec "$host" sh -c 'mount --bind "$1" /dev/shm && shift && exec "$@"' sh "$netns_shm_root/h$1" "${@:2}"
}

# netns_spawn I COMMAND... &: as netns_exec, for a background job: the job's subshell becomes the
# command (exec), so $! is the command's own pid and a signal sent to it reaches the command.
netns_spawn() {
  local host
  host="$(netns_host "$1")"
  exec ip netns exec "$host" sh -c 'mount --bind "$1" /dev/shm && shift && exec "$@"' sh "$netns_shm_root/h$1" "${@:2}"
}

# netns_link I up|down: plugs or pulls host I's cable (its port on the switch).
netns_link() { ip -n "$(netns_switch)" link set "p$1" "$2"; }

# netns_check_isolated: every interface in our namespaces is lo, br0, eth0 or p<i>, and each veth's
# peer is in one of our namespaces (so none reaches the root namespace). Prints the problem, if any.
netns_check_isolated() {
  local ns bad=0 line
  for ns in "${netns_names[@]}"; do
    while read -r line; do
      case "$line" in
        lo | br0 | eth0 | p[0-9]*) ;;
        *) echo "unexpected interface $line in $ns"; bad=1 ;;
      esac
    done < <(ip -n "$ns" -o link show | awk -F': ' '{print $2}' | sed 's/@.*//')
    # A veth whose peer sits in another namespace shows "link-netns <name>" (or link-netnsid):
    # the peer namespace must be one of ours.
    while read -r peer; do
      [ -z "$peer" ] && continue
      case " ${netns_names[*]} " in
        *" $peer "*) ;;
        *) echo "a veth in $ns has its peer in namespace '$peer'"; bad=1 ;;
      esac
    done < <(ip -n "$ns" -d link show type veth | sed -n 's/.*link-netns \([^ ]*\).*/\1/p')
  done
  return "$bad"
}

# netns_pids: processes running in our namespaces.
netns_pids() {
  local ns
  for ns in "${netns_names[@]}"; do ip netns pids "$ns" 2>/dev/null; done
}

netns_cleanup() {
  local pid ns
  for pid in $(netns_pids); do kill -INT "$pid" 2>/dev/null || true; done
  for _ in $(seq 20); do [ -z "$(netns_pids)" ] && break; sleep 0.1; done
  for pid in $(netns_pids); do kill -KILL "$pid" 2>/dev/null || true; done
  for ns in "${netns_names[@]}"; do ip netns del "$ns" 2>/dev/null || true; done
  netns_names=()
  rm -rf "$netns_shm_root"
}

# The common start of a multihost test (after sourcing lib.sh and this file): errors outside a
# check count as failures (also inside functions), skip (77) unless namespaces can be made, and
# delete every namespace on any exit.
netns_test_start() {
  set -eE
  trap 'failures=$((failures + 1)); echo "FAIL: unexpected error at line $LINENO"' ERR
  netns_require
  netns_reap_stale
  trap 'netns_cleanup; cleanup' EXIT
  trap 'exit 143' TERM INT
}
