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
  for (const char* ch : {kFlowChannel, kFrdAckChannel})
    data_.subscribe(ch, &AnalyzerNode::on_control, this)->setQueueCapacity(100000);
}

void AnalyzerNode::announce_ready() { ack("ready", -1); }

void AnalyzerNode::ack(const std::string& stream, int64_t seq) {
  publish_ack(control_, feeder_.run_id(), name_, stream, seq);
}

void AnalyzerNode::on_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    const int64_t tape0 = feeder_.tape_delivered(), status0 = feeder_.status_delivered();
    const TapeFeeder::Fed fed =
        feeder_.feed(channel, rbuf->data, static_cast<int>(rbuf->data_size));
    if (fed.kind == TapeFeeder::Kind::kOther) return;
    started_ = true;
    for (auto& a : feeder_.analyzers()) {
      std::vector<FrdPoint> fresh = a->take_new_points();
      if (fresh.empty()) continue;
      // While the curve grows, only the points this block completed travel (not the whole curve
      // again each time); the finished curve travels whole (merged repeats, the BLA).
      const Frd f = a->done() ? a->frd() : Frd{a->pair(), std::move(fresh), ""};
      frd_t m = to_frd_msg(f, feeder_.run_id(), frd_seq_++, a->done());
      data_.publish(kFrdChannel, &m);
    }
    if (feeder_.status_delivered() != status0 ||
        (fed.kind == TapeFeeder::Kind::kStatus && fed.duplicate))
      ack("status", feeder_.status_delivered());
    if (feeder_.tape_delivered() != tape0 || (fed.kind == TapeFeeder::Kind::kTape && fed.duplicate))
      ack("tape", feeder_.tape_delivered());
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

void AnalyzerNode::on_control(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  try {
    if (channel == kFlowChannel) {
      const flow_t f = decode_checked<flow_t>(rbuf, channel);
      if (f.kind == "close" && (feeder_.run_id().empty() || f.run_id == feeder_.run_id()))
        closed_ = true;
      return;
    }
    const ack_t a = decode_checked<ack_t>(rbuf, channel);
    if (a.consumer != "identify" || (!feeder_.run_id().empty() && a.run_id != feeder_.run_id()))
      return;
    identifier_heard_ = true;
    if (a.stream.rfind("frd:", 0) == 0) taken_.insert(a.stream.substr(4));
  } catch (const std::exception& e) {
    if (error_.empty()) error_ = e.what();
  }
}

std::vector<Frd> AnalyzerNode::finish() {
  final_.clear();
  for (auto& a : feeder_.analyzers()) final_.push_back(a->frd());
  republish_untaken();
  return final_;
}

bool AnalyzerNode::curves_taken() const {
  for (const Frd& f : final_)
    if (!taken_.count(f.pair)) return false;
  return true;
}

void AnalyzerNode::republish_untaken() {
  for (const Frd& f : final_) {
    if (taken_.count(f.pair)) continue;
    frd_t m = to_frd_msg(f, feeder_.run_id(), frd_seq_++, true);
    data_.publish(kFrdChannel, &m);
  }
}

}  // namespace fralab
