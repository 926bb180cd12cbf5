#!/usr/bin/env bash
# Two "hosts" on one machine: network namespaces A and B joined by a veth pair (10.77.0.1 and
# 10.77.0.2, multicast routed over it), nothing else. Runs `fralab-deputy --name A` in A and the
# given command in B, with FRALAB_NETWORK=1 (the multi-host opt-in); the deputy is stopped after.
# Usage: two_hosts.sh BIN_DIR command [args...]   (needs root and iproute2)
set -euo pipefail
bin=$1
shift
a=fralabA$$
b=fralabB$$
cleanup() {
  [ -n "${dep:-}" ] && kill "$dep" 2>/dev/null && wait "$dep" 2>/dev/null
  ip netns del "$a" 2>/dev/null || true
  ip netns del "$b" 2>/dev/null || true
}
trap cleanup EXIT
ip netns add "$a"
ip netns add "$b"
ip link add "va$$" netns "$a" type veth peer name "vb$$" netns "$b"
for ns in "$a" "$b"; do ip -n "$ns" link set lo up; done
ip -n "$a" addr add 10.77.0.1/24 dev "va$$"
ip -n "$b" addr add 10.77.0.2/24 dev "vb$$"
ip -n "$a" link set "va$$" up multicast on
ip -n "$b" link set "vb$$" up multicast on
ip -n "$a" route add 224.0.0.0/4 dev "va$$"
ip -n "$b" route add 224.0.0.0/4 dev "vb$$"
export FRALAB_NETWORK=1
ip netns exec "$a" "$bin/fralab-deputy" --name A > "${TMPDIR:-/tmp}/fralab-deputy-$$.log" 2>&1 &
dep=$!
ip netns exec "$b" "$@"
