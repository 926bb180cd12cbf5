#include "recorder_node.h"

#include <cstdio>

#include "fralab/lcm_io.h"

namespace fralab {

RecorderNode::RecorderNode(lcm::LCM& data, lcm::LCM& control, const std::string& path,
                           std::string run_id, std::string name)
    : data_(data),
      control_(control),
      path_(path),
      run_id_(std::move(run_id)),
      name_(std::move(name)),
      log_(std::make_unique<lcm::LogFile>(path, "w")) {
  if (!log_->good()) throw InputError(path + ": cannot create the tape file");
  sub_ = data_.subscribe(".*", &RecorderNode::on_any, this);
  sub_->setQueueCapacity(100000);
}

RecorderNode::~RecorderNode() {
  data_.unsubscribe(sub_);
  if (log_) std::fflush(log_->getFilePtr());
}

void RecorderNode::announce_ready() { ack(-1); }

void RecorderNode::ack(int64_t seq) {
  ack_t a;
  a.run_id = run_id_;
  a.consumer = name_;
  a.seq = seq;
  control_.publish(kAckChannel, &a);
}

void RecorderNode::on_any(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    lcm::LogEvent ev;
    ev.eventnum = events_;
    ev.timestamp = rbuf->recv_utime;
    ev.channel = channel;
    ev.datalen = int32_t(rbuf->data_size);
    ev.data = rbuf->data;
    if (log_->writeEvent(&ev) != 0 || std::fflush(log_->getFilePtr()) != 0)
      throw InputError(path_ + ": write failed at event " + std::to_string(events_) +
                       " (disk full?)");
    ++events_;
    if (channel != kTapeChannel) return;
    const tape_block_t m = decode_checked<tape_block_t>(rbuf, channel);
    if (run_id_.empty()) run_id_ = m.run_id;
    if (m.run_id != run_id_) return;
    ++blocks_;
    ack(m.seq);  // on disk: the acquisition may go on
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

}  // namespace fralab
