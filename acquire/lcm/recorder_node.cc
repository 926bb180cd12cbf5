#include "recorder_node.h"

#include <cstdio>

#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/lab_lcm.h"

namespace fralab {

RecorderNode::RecorderNode(lcm::LCM& data, lcm::LCM& control, const std::string& path,
                           std::string run_id, std::string name, bool append, int64_t first_block,
                           int64_t first_status)
    : data_(data),
      control_(control),
      path_(path),
      run_id_(std::move(run_id)),
      name_(std::move(name)),
      log_(std::make_unique<lcm::LogFile>(path, append ? "a" : "w")),
      tape_(first_block),
      status_(first_status) {
  if (!log_->good()) throw InputError(path + ": cannot create the tape file");
  sub_ = data_.subscribe(".*", &RecorderNode::on_any, this);
  sub_->setQueueCapacity(100000);
}

RecorderNode::~RecorderNode() {
  data_.unsubscribe(sub_);
  if (log_) std::fflush(log_->getFilePtr());
}

void RecorderNode::announce_ready() { ack("ready", -1); }

void RecorderNode::ack(const std::string& stream, int64_t seq) {
  publish_ack(control_, run_id_, name_, stream, seq);
}

void RecorderNode::on_any(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    // Another run sharing the port (its datagrams reach every socket bound to it): not ours.
    if (!run_id_.empty() && channel.rfind("FRALAB_", 0) == 0) {
      const auto id = peek_run_id(rbuf->data, rbuf->data_size);
      if (id && *id != run_id_) return;
    }
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
    // On disk: acknowledge the position without a gap (again for a duplicate).
    auto advance = [&](InOrder<char>& q, int64_t seq, const char* stream) {
      if (q.offer(seq, 0) == InOrder<char>::Offer::kNew) {
        const int64_t before = q.delivered();
        while (q.pop()) {
        }
        if (q.delivered() == before) return;
      }
      ack(stream, q.delivered());
    };
    if (channel == kTapeChannel) {
      Block m;
      try {
        m = decode_tape_block(rbuf, channel);
      } catch (const CorruptBlock&) {
        return;  // on the tape as it came, not acknowledged: it is sent again
      }
      if (run_id_.empty()) run_id_ = m.run_id;
      if (m.run_id != run_id_) return;
      ++blocks_;
      advance(tape_, m.seq, "tape");
    } else if (channel == kStatusChannel) {
      const StatusEvent m = decode_status_event(rbuf, channel);
      if (run_id_.empty()) run_id_ = m.run_id;
      if (m.run_id != run_id_ || m.seq < 0) return;
      advance(status_, m.seq, "status");
    }
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

}  // namespace fralab
