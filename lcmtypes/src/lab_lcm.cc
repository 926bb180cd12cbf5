#include "fralab/lcm/lab_lcm.h"

#include <sys/select.h>

#include <algorithm>

#include "fralab/core/error.h"
#include "fralab/lcm/url.h"

namespace fralab {

void require_lcm(lcm::LCM& lcm, const std::string& what, const std::string& url) {
  if (!lcm.good()) throw InputError("cannot open " + what + " at " + url);
  if (lcm.getFileno() < 0)
    throw InputError("cannot receive on " + what + " at " + url +
                     ": its port is held by another socket (bind failed; see the line above)");
}

LabLcm::LabLcm(const std::string& url, const std::string& ctl_url)
    : data_url(resolve_lcm_url(url)),
      control_url(ctl_url.empty() ? control_url_for(data_url) : resolve_lcm_url(ctl_url)),
      data(data_url),
      control(control_url) {
  require_lcm(data, "LCM", data_url);
  require_lcm(control, "the control LCM URL", control_url);
}

void publish_ack(lcm::LCM& control, const std::string& run_id, const std::string& consumer,
                 const std::string& stream, int64_t seq, const char* channel) {
  ack_t a;
  a.run_id = run_id;
  a.consumer = consumer;
  a.stream = stream;
  a.seq = seq;
  control.publish(channel, &a);
}

void publish_flow(lcm::LCM& control, const std::string& run_id, const std::string& kind,
                  const std::string& stream, int64_t from_seq, int64_t to_seq) {
  flow_t f;
  f.run_id = run_id;
  f.kind = kind;
  f.stream = stream;
  f.from_seq = from_seq;
  f.to_seq = to_seq;
  control.publish(kFlowChannel, &f);
}

void handle_either(lcm::LCM& a, lcm::LCM& b, int timeout_ms) {
  if (&a == &b) {  // one instance for data and control (memq:// in tests)
    a.handleTimeout(timeout_ms);
    return;
  }
  fd_set fds;
  FD_ZERO(&fds);
  const int fa = a.getFileno(), fb = b.getFileno();
  FD_SET(fa, &fds);
  FD_SET(fb, &fds);
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  if (select(std::max(fa, fb) + 1, &fds, nullptr, nullptr, &tv) <= 0) return;
  if (FD_ISSET(fa, &fds)) a.handle();
  if (FD_ISSET(fb, &fds)) b.handle();
}

}  // namespace fralab
