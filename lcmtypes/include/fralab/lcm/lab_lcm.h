// The LCM instances of a lab process: opened and checked (a socket that cannot bind is an error,
// not a later crash), waited on together, and the flow-control messages every node publishes
// (acknowledgements, resend/close requests).
#pragma once

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "fralab/ack_t.hpp"
#include "fralab/flow_t.hpp"
#include "fralab/lcm/channels.h"

namespace fralab {

/// Publishes an acknowledgement (ack_t.lcm: consumer, stream, seq) on `channel` (kAckChannel on
/// the control instance; kFrdAckChannel on the data instance for the identifier's).
void publish_ack(lcm::LCM& lcm, const std::string& run_id, const std::string& consumer,
                 const std::string& stream, int64_t seq, const char* channel = kAckChannel);
/// Publishes a flow-control request (flow_t.lcm: "resend" or "close") on the data instance.
void publish_flow(lcm::LCM& data, const std::string& run_id, const std::string& kind,
                  const std::string& stream, int64_t from_seq, int64_t to_seq);

/// Throws InputError naming `what` and `url` unless `lcm` can publish and receive there. LCM opens
/// its receive socket lazily (at the first subscription or getFileno()): a bind that fails there
/// (the port held by a socket without SO_REUSEADDR: "bind: Address already in use") is only
/// printed, and LCM 1.3 then crashed the process at a later call (fralab-acquire: signal 11). The
/// socket is opened here, once, and its failure is an error.
void require_lcm(lcm::LCM& lcm, const std::string& what, const std::string& url);

/// The two LCM instances of a lab process: the tape's (data) and the control URL's, each opened
/// and checked with require_lcm. data_url: resolve_lcm_url(url); control_url: ctl_url resolved
/// when given, else control_url_for(data_url). Throws InputError naming the URL that fails.
struct LabLcm {
  LabLcm(const std::string& url, const std::string& ctl_url);
  std::string data_url, control_url;
  lcm::LCM data, control;
};

/// Waits up to timeout_ms for traffic on either instance and dispatches what arrived (a and b may
/// be the same instance).
void handle_either(lcm::LCM& a, lcm::LCM& b, int timeout_ms);

}  // namespace fralab
