#include "plant_node.h"

namespace fralab {

PlantNode::PlantNode(lcm::LCM& data, lcm::LCM& control, LockstepPlant plant, size_t keep_blocks,
                     int tick_samples)
    : plant_(std::move(plant)),
      data_(data),
      control_(control),
      keep_(keep_blocks),
      commands_(plant_.next_seq()) {
  data_.subscribe(kCmdChannel, &PlantNode::on_command, this)->setQueueCapacity(100000);
  data_.subscribe(kFlowChannel, &PlantNode::on_flow, this)->setQueueCapacity(100000);
  if (tick_samples > 0) buffer_.emplace(tick_samples);
}

void PlantNode::publish_tape(const Block& b) {
  tape_block_t msg = to_tape_msg(b);
  data_.publish(kTapeChannel, &msg);
  kept_[msg.seq] = std::move(msg);
  while (kept_.size() > keep_) kept_.erase(kept_.begin());
}

bool PlantNode::tick() {
  if (!buffer_ || !error_.empty()) return false;
  try {
    std::optional<Block> cmd = buffer_->next();
    if (!cmd || plant_.done()) return false;
    publish_tape(plant_.advance(*cmd));
    return true;
  } catch (const std::exception& e) {
    error_ = e.what();
    return false;
  }
}

void PlantNode::announce_ready() { ack("ready", -1); }

void PlantNode::ack(const std::string& stream, int64_t seq) {
  publish_ack(control_, plant_.run_id(), "plant", stream, seq);
}

void PlantNode::on_command(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    Block cmd = from_msg(decode_checked<command_block_t>(rbuf, channel));
    if (!plant_.accepts(cmd.run_id)) return;  // another run on the same URL: not ours
    started_ = true;
    if (cmd.seq < 0) {  // the acquisition was stopped: actuators to their operating point
      if (!plant_.done()) {
        tape_block_t msg = to_tape_msg(plant_.hold(cmd));
        data_.publish(kTapeChannel, &msg);
      }
      return;
    }
    const int64_t seq = cmd.seq;
    if (buffer_) {  // free-running: buffered by its samples, the contiguous part acknowledged
      if (!plant_.done()) buffer_->add(cmd);
      if (commands_.offer(seq, std::move(cmd)) != InOrder<Block>::Offer::kDuplicate)
        while (commands_.pop()) {
        }
      ack("command", commands_.delivered());
      return;
    }
    if (plant_.done() ||
        commands_.offer(seq, std::move(cmd)) == InOrder<Block>::Offer::kDuplicate) {
      ack("command", commands_.delivered());  // its acknowledgement was lost: say it again
      return;
    }
    bool moved = false;
    while (auto c = commands_.pop()) {
      publish_tape(plant_.advance(*c));
      moved = true;
    }
    if (moved) ack("command", commands_.delivered());
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

void PlantNode::on_flow(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if (!error_.empty()) return;
  try {
    const flow_t f = decode_checked<flow_t>(rbuf, channel);
    if (plant_.run_id().empty() || f.run_id != plant_.run_id()) return;
    if (f.kind == "close") {
      closed_ = true;
    } else if (f.kind == "resend" && f.stream == "tape") {
      for (int64_t s = f.from_seq; s <= f.to_seq; ++s) {
        auto it = kept_.find(s);
        if (it == kept_.end()) {
          if (s < plant_.next_seq() && warnings_.size() < 2000)
            warnings_ += "tape block " + std::to_string(s) +
                         " was asked for again but is no longer kept (keeps the last " +
                         std::to_string(keep_) + ")\n";
          continue;
        }
        data_.publish(kTapeChannel, &it->second);
        ++resent_;
      }
    }
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

}  // namespace fralab
