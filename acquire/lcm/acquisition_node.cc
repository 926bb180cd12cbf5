#include "acquisition_node.h"

#include <algorithm>
#include <chrono>
#include <functional>

#include "fralab/lcm_io.h"

namespace fralab {
namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

// Acknowledgements on the control instance, for this run only.
struct AcquisitionNode::Acks {
  std::string run_id;
  AckTracker acks;
  std::string error;
  void on_ack(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    try {
      ack_t a = decode_checked<ack_t>(rbuf, ch);
      if (!a.run_id.empty() && a.run_id != run_id) return;
      acks.on_ack(a.consumer, a.seq);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
};

AcquisitionNode::AcquisitionNode(lcm::LCM& data, lcm::LCM& control, const Campaign& campaign,
                                 AcquisitionLoopOptions o)
    : data_(data),
      control_(control),
      campaign_(campaign),
      o_(std::move(o)),
      acks_(std::make_unique<Acks>()) {
  acks_->run_id = o_.run_id;
  sub_ = control_.subscribe(kAckChannel, &Acks::on_ack, acks_.get());
  sub_->setQueueCapacity(100000);
}

AcquisitionNode::~AcquisitionNode() { control_.unsubscribe(sub_); }

Json AcquisitionNode::run() {
  lcm::LCM& data = data_;
  lcm::LCM& control = control_;
  const Campaign& campaign = campaign_;
  const AcquireOptions& o = o_.acquire;
  Acks& acq = *acks_;
  std::vector<std::string> consumers = o_.consumers;
  if (std::find(consumers.begin(), consumers.end(), "plant") == consumers.end())
    consumers.push_back("plant");

  // Waits until every consumer has acknowledged `target` (-1: ready); past `timeout` seconds the
  // error names the slowest consumer (`lag`) through `why`.
  std::string lag;
  auto wait_acks = [&](int64_t target, double timeout, int poll_ms,
                       const std::function<std::string()>& why) {
    const auto t = Clock::now();
    while (acq.acks.min_ack(consumers, &lag) < target) {
      handle_either(data, control, poll_ms);
      if (!acq.error.empty()) throw InputError(acq.error);
      if (std::chrono::duration<double>(Clock::now() - t).count() > timeout)
        throw InputError(why());
    }
  };
  wait_acks(-1, o_.ready_timeout_s, 50, [&] {
    return "consumer \"" + lag + "\" never said ready within " +
           std::to_string(o_.ready_timeout_s) + " s (is it running on the same LCM URL?)";
  });
  auto publish_status = [&](const StatusEvent& e) {
    excitation_status_t m = to_status_msg(e);
    data.publish(kStatusChannel, &m);
  };
  StatusEvent start = campaign.events().front();
  start.state = RunState::kStart;
  start.seq = -1;
  start.sample = 0;
  start.n_samples = campaign.total_samples();
  publish_status(start);

  const auto t0 = Clock::now();
  const int64_t total = campaign.total_samples();
  const int64_t nblocks = command_block_count(campaign, o.block);
  size_t ev = 0;
  for (int64_t b = 0; b < nblocks; ++b) {
    wait_acks(b - o.window, o_.stall_timeout_s, 20, [&] {
      return "consumer \"" + lag + "\" stopped acknowledging at block " +
             std::to_string(acq.acks.min_ack(consumers, nullptr)) + " (sent up to " +
             std::to_string(b - 1) + ")";
    });
    const Block blk = command_block(campaign, b, o.block, o.sample_rate_hz, o_.run_id);
    if (o.speed > 0) {
      auto due =
          t0 + std::chrono::duration<double>(double(blk.start_sample) / o.sample_rate_hz / o.speed);
      while (Clock::now() < due)
        handle_either(
            data, control,
            1 + int(std::chrono::duration<double, std::milli>(due - Clock::now()).count()));
    }
    while (ev < campaign.events().size() &&
           (campaign.events()[ev].sample < blk.start_sample + blk.n_samples || blk.final_block))
      publish_status(campaign.events()[ev++]);
    command_block_t m = to_command_msg(blk);
    data.publish(kCmdChannel, &m);
  }
  // Wait for everyone to take the last block.
  wait_acks(nblocks - 1, o_.stall_timeout_s, 20, [&] {
    return "consumer \"" + lag + "\" did not acknowledge the final block " +
           std::to_string(nblocks - 1);
  });
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  const double engine_s = double(total) / o.sample_rate_hz;
  Json sj{{"run_id", o_.run_id},
          {"engine_time_s", engine_s},
          {"wall_time_s", wall},
          {"speedup", engine_s / std::max(wall, 1e-9)},
          {"blocks", nblocks},
          {"samples", total},
          {"excitation", to_string(campaign.events().front().excitation)}};
  return sj;
}

}  // namespace fralab
