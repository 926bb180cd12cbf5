#include "plant_node.h"

#include <chrono>
#include <random>

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

void ServeOptions::validate() const {
  if (free_running && (!(speed > 0) || tick < 1 || jitter_ms < 0))
    throw InputError(
        "--free-running needs --speed > 0, --tick >= 1, --jitter-ms >= 0 and no --replay");
}

void serve(PlantNode& plant, lcm::LCM& lcm, const ServeOptions& o) {
  o.validate();
  using Clock = std::chrono::steady_clock;
  auto last_ready = Clock::now() - std::chrono::seconds(1);
  // After the final block the plant stays to republish tape blocks a consumer lost, until the
  // acquisition's close (or linger_s without it: the acquisition is gone).
  Clock::time_point done_at{};
  const double period_s = double(o.tick) / (o.sample_rate_hz * o.speed);
  std::mt19937_64 rng(o.seed ^ 0x6a09e667f3bcc909ULL);
  std::uniform_real_distribution<double> jitter(-o.jitter_ms * 1e-3, o.jitter_ms * 1e-3);
  Clock::time_point t0{}, due{};
  int64_t ticks = 0;
  while (o.keep_running || !(plant.done() && plant.closed())) {
    if (o.free_running && plant.started() && !plant.done()) {
      if (t0 == Clock::time_point{}) {
        t0 = Clock::now();
        due = t0 + std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>(period_s + jitter(rng)));
      }
      while (!plant.done() && Clock::now() >= due) {
        plant.tick();
        ++ticks;
        due = t0 + std::chrono::duration_cast<Clock::duration>(
                       std::chrono::duration<double>(double(ticks + 1) * period_s + jitter(rng)));
      }
      const double wait_ms = std::chrono::duration<double, std::milli>(due - Clock::now()).count();
      lcm.handleTimeout(std::max(1, std::min(100, int(wait_ms))));
      if (!plant.error().empty()) throw InputError(plant.error());
      continue;
    }
    if (!plant.started() &&
        std::chrono::duration<double>(Clock::now() - last_ready).count() > 0.1) {
      plant.announce_ready();  // the acquisition waits for this before the first command
      last_ready = Clock::now();
    }
    lcm.handleTimeout(100);  // the control URL is only published to
    if (!plant.error().empty()) throw InputError(plant.error());
    if (plant.done() && done_at == Clock::time_point{}) done_at = Clock::now();
    if (!o.keep_running && plant.done() &&
        std::chrono::duration<double>(Clock::now() - done_at).count() > o.linger_s)
      break;
  }
}

}  // namespace fralab
