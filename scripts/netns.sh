#!/usr/bin/env bash
# Runs a command in a private network namespace: only `lo`, multicast on, 224.0.0.0/4 routed to lo,
# so LCM traffic (udpm, ttl=0) can never reach another host. Needs root (CI runs as root).
set -euo pipefail
exec unshare -n bash -c 'ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec "$@"' netns "$@"
