// The LCM URL policy: fralab traffic never leaves the host unless asked (udpm URLs carry ttl=0;
// ttl >= 1 needs FRALAB_NETWORK=1), a private URL per lab run, and the control URL beside the
// tape's. Pure string work: nothing here opens a socket.
#pragma once

#include <cstdint>
#include <string>
#include <utility>

namespace fralab {

/// The LCM URL: `flag` when given, else $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0.
/// A udpm URL must state its ttl option (parsed from the query: "?a=1&ttl=0", a number 0-255
/// without leading zeros): ttl=0 keeps fralab traffic on this host; ttl >= 1 (reaching other
/// hosts) is refused unless the environment says FRALAB_NETWORK=1 (the explicit opt-in).
std::string resolve_lcm_url(const std::string& flag);

/// The kernel's ephemeral port range, inclusive (/proc/sys/net/ipv4/ip_local_port_range; Linux's
/// default 32768-60999 when it cannot be read).
std::pair<int, int> ephemeral_port_range();

/// A fresh private URL for one lab run: a multicast group and an even port P of 10000-65534 derived
/// from `salt`, P and P + 1 (the control URL's) outside the ephemeral range (13652 ports with
/// Linux's default; Linux separates runs by port, not group, and LCM's unbound send sockets take
/// ephemeral ports a receiver could then not bind), ttl=0, and a 2 MB receive buffer request
/// (granted up to net.core.rmem_max). The one-argument form reads the range from the kernel.
std::string private_lcm_url(uint64_t salt);
std::string private_lcm_url(uint64_t salt, std::pair<int, int> ephemeral);

/// The control URL of a lab run: flow-control acknowledgements travel there, away from the tape
/// URL, so lcm-logger (whose subscription queue holds 30 messages) hears only the tape traffic.
/// Derived from the tape URL by adding 1 to its port ("" stays "").
std::string control_url_for(const std::string& tape_url);

}  // namespace fralab
