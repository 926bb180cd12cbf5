#!/usr/bin/env bash
# Runs a command in a private network namespace (as netns.sh) whose UDP traffic loses a random
# fraction of datagrams, injected with nftables: every datagram (every LCM channel, both
# directions, multicast on lo) is dropped with probability PER_MILLE/1000.
# Usage: lossy.sh PER_MILLE command [args...]   (needs root and nftables)
set -euo pipefail
loss=$1
shift
command -v nft >/dev/null || { echo "lossy.sh: nft not found (apt-get install nftables)" >&2; exit 2; }
exec unshare -n bash -c '
  set -e
  ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo
  nft add table inet fralab_loss
  nft add chain inet fralab_loss out "{ type filter hook output priority 0; policy accept; }"
  nft add rule inet fralab_loss out meta l4proto udp numgen random mod 1000 "<" '"$loss"' counter drop
  "$@"
  rc=$?
  echo "lossy.sh: $(nft list chain inet fralab_loss out | grep -o "packets [0-9]*" | head -1) dropped" >&2
  exit $rc' lossy "$@"
