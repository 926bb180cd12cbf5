#include "identifier_node.h"

#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/lab_lcm.h"

namespace fralab {

IdentifierNode::IdentifierNode(lcm::LCM& data, std::string run_id)
    : data_(data), run_id_(std::move(run_id)) {
  sub_ = data_.subscribe(kFrdChannel, &IdentifierNode::on_frd, this);
  sub_->setQueueCapacity(100000);
}

IdentifierNode::~IdentifierNode() { data_.unsubscribe(sub_); }

void IdentifierNode::announce_ready() {
  publish_ack(data_, run_id_, "identify", "ready", -1, kFrdAckChannel);
}

void IdentifierNode::on_frd(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    const frd_t m = decode_checked<frd_t>(rbuf, channel);
    if (!run_id_.empty() && m.run_id != run_id_) return;
    if (!m.complete) return;
    if (!curves_.count(m.pair)) curves_[m.pair] = from_frd_msg(m);
    publish_ack(data_, m.run_id, "identify", "frd:" + m.pair, 0, kFrdAckChannel);
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

std::vector<FitResult> IdentifierNode::fit_and_publish(const FitOptions& o, const std::string& out,
                                                       const std::string& title) {
  std::vector<Frd> curves;
  for (const auto& [pair, f] : curves_) curves.push_back(f);
  std::vector<FitResult> fits = fit_and_write(curves, o, out, title);
  for (size_t i = 0; i < fits.size(); ++i) {
    tf_t m = to_tf_msg(fits[i].tf, curves[i].pair, run_id_, fits[i].e_n, fits[i].status_str());
    data_.publish(kTfChannel, &m);
  }
  return fits;
}

}  // namespace fralab
