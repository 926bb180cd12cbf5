#include "fralab/lcm/url.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "fralab/core/error.h"
#include "fralab/core/text.h"

namespace fralab {

std::string resolve_lcm_url(const std::string& flag) {
  std::string url = flag;
  if (url.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    url = env && *env ? env : "udpm://239.255.76.67:7667?ttl=0";
  }
  if (url.rfind("udpm://", 0) != 0) return url;
  // The ttl option, parsed: "?a=1&ttl=0&b=2"; it must be stated.
  long ttl = -2;  // unstated
  const auto q = url.find('?');
  if (q != std::string::npos) {
    for (const std::string& kv : split_list(url.substr(q + 1), '&')) {
      const auto eq = kv.find('=');
      if (kv.substr(0, eq) != "ttl") continue;
      const std::string v = eq == std::string::npos ? "" : kv.substr(eq + 1);
      char* end = nullptr;
      ttl = v.empty() || v.size() > 3 ? -1 : std::strtol(v.c_str(), &end, 10);
      if (ttl < 0 || ttl > 255 || end != v.c_str() + v.size() || (v.size() > 1 && v[0] == '0'))
        throw InputError("LCM URL \"" + url + "\": ttl \"" + v + "\" is not a number 0-255");
    }
  }
  const char* net = std::getenv("FRALAB_NETWORK");
  const bool network = net && std::string(net) == "1";
  if (ttl == -2)
    throw InputError("LCM URL \"" + url +
                     "\" states no ttl: fralab traffic stays on this host unless asked; append "
                     "?ttl=0");
  if (ttl > 0 && !network)
    throw InputError("LCM URL \"" + url + "\" has ttl=" + std::to_string(ttl) +
                     ": fralab traffic stays on this host; reaching other hosts is an explicit "
                     "opt-in: set FRALAB_NETWORK=1");
  return url;
}

std::pair<int, int> ephemeral_port_range() {
  int lo = 32768, hi = 60999;  // Linux's default
  if (std::FILE* f = std::fopen("/proc/sys/net/ipv4/ip_local_port_range", "r")) {
    int a = 0, b = 0;
    if (std::fscanf(f, "%d %d", &a, &b) == 2 && a > 0 && b >= a && b <= 65535) lo = a, hi = b;
    std::fclose(f);
  }
  return {lo, hi};
}

std::string private_lcm_url(uint64_t salt) { return private_lcm_url(salt, ephemeral_port_range()); }

std::string private_lcm_url(uint64_t salt, std::pair<int, int> ephemeral) {
  // Group 239.255.x.y (administratively scoped), an even port P of 10000-65534 with P and P + 1
  // (the control URL's) outside the kernel's ephemeral range, ttl=0. Linux hands a multicast
  // datagram to every socket bound to its port whatever the group, so the port is what separates
  // two runs. Outside the ephemeral range because LCM's send sockets are never bound: each takes an
  // ephemeral port at its first datagram, without SO_REUSEADDR, and a receiver's bind to that port
  // then fails ("bind: Address already in use"; a full test run meets it with tape ports in
  // 20000-59998).
  const auto [lo, hi] = ephemeral;
  const int a_end = std::min(lo - 2, 65534);  // segment A: even P in [10000, a_end], P + 1 < lo
  const int b_begin = std::max(10000, (hi + 2) / 2 * 2);  // segment B: even P >= hi + 1
  const int na = a_end >= 10000 ? (a_end - 10000) / 2 + 1 : 0;
  const int nb = b_begin <= 65534 ? (65534 - b_begin) / 2 + 1 : 0;
  const unsigned x = 1 + (salt % 250), y = 1 + ((salt / 250) % 250);
  unsigned port;
  if (na + nb == 0) {  // the whole range is ephemeral: nothing better than any even port
    port = 10000 + 2 * unsigned((salt / 62500) % 27768);
  } else {
    const int k = int((salt / 62500) % uint64_t(na + nb));
    port = unsigned(k < na ? 10000 + 2 * k : b_begin + 2 * (k - na));
  }
  return "udpm://239.255." + std::to_string(x) + "." + std::to_string(y) + ":" +
         std::to_string(port) + "?ttl=0&recv_buf_size=2097152";
}

std::string control_url_for(const std::string& url) {
  // udpm://GROUP:PORT?opts -> udpm://GROUP:PORT+1?opts
  auto colon = url.rfind(':');
  auto q = url.find('?', colon == std::string::npos ? 0 : colon);
  if (url.rfind("udpm://", 0) != 0 || colon == std::string::npos || colon < 7) return url;
  std::string port = url.substr(colon + 1, (q == std::string::npos ? url.size() : q) - colon - 1);
  try {
    return url.substr(0, colon + 1) + std::to_string(std::stoi(port) + 1) +
           (q == std::string::npos ? "" : url.substr(q));
  } catch (const std::exception&) {
    return url;
  }
}

}  // namespace fralab
