#!/usr/bin/env bash
# Runs a multi-process test isolated from the network: in a private network namespace when the
# kernel allows it (root), else directly. Either way every fralab run uses its own multicast
# group/port with ttl=0 (lcm_io.h private_lcm_url), so nothing reaches another host.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if unshare -n true 2>/dev/null; then
  exec "$here/netns.sh" "$@"
fi
echo "isolated.sh: no network namespace here (not root?); relying on private LCM URLs with ttl=0" >&2
exec "$@"
