#include "analyzer_node.h"

namespace fralab {

AnalyzerNode::AnalyzerNode(lcm::LCM& data, lcm::LCM& control, const std::vector<std::string>& pairs,
                           const AnalyzerOptions& opt, std::string name, std::string run_id)
    : feeder_(pairs, opt, std::move(run_id)),
      data_(data),
      control_(control),
      name_(name.empty() ? pairs.front() : std::move(name)) {
  for (const char* ch : {kTapeChannel, kStatusChannel})
    data_.subscribe(ch, &AnalyzerNode::on_msg, this)->setQueueCapacity(100000);
}

void AnalyzerNode::announce_ready() { ack(-1); }

void AnalyzerNode::ack(int64_t seq) {
  ack_t a;
  a.run_id = feeder_.run_id();
  a.consumer = name_;
  a.seq = seq;
  control_.publish(kAckChannel, &a);
}

void AnalyzerNode::on_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    started_ = true;
    const int64_t seq = feeder_.feed(channel, rbuf->data, static_cast<int>(rbuf->data_size));
    for (auto& a : feeder_.analyzers()) {
      if (!a->take_new_points().empty()) {
        frd_t m = to_frd_msg(a->frd(), feeder_.run_id(), frd_seq_++, a->done());
        data_.publish(kFrdChannel, &m);
      }
    }
    if (seq >= 0) ack(seq);
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

std::vector<Frd> AnalyzerNode::finish() {
  std::vector<Frd> frds;
  for (auto& a : feeder_.analyzers()) {
    frds.push_back(a->frd());
    frd_t m = to_frd_msg(frds.back(), feeder_.run_id(), frd_seq_++, true);
    data_.publish(kFrdChannel, &m);
  }
  return frds;
}

}  // namespace fralab
