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
  Acks(std::string id, FlowControl f) : run_id(std::move(id)), flow(std::move(f)) {}
  std::string run_id;
  FlowControl flow;
  Clock::time_point t0 = Clock::now();
  std::string error;
  double now() const { return std::chrono::duration<double>(Clock::now() - t0).count(); }
  void on_ack(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    try {
      ack_t a = decode_checked<ack_t>(rbuf, ch);
      if (!a.run_id.empty() && a.run_id != run_id) return;
      flow.on_ack(a.consumer, a.stream, a.seq, now());
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
      acks_(std::make_unique<Acks>(o_.run_id, FlowControl(o_.consumers, o_.flow))) {
  sub_ = control_.subscribe(kAckChannel, &Acks::on_ack, acks_.get());
  sub_->setQueueCapacity(100000);
}

AcquisitionNode::~AcquisitionNode() { control_.unsubscribe(sub_); }

Json AcquisitionNode::run() {
  lcm::LCM& data = data_;
  const Campaign& campaign = campaign_;
  const AcquireOptions& o = o_.acquire;
  Acks& acq = *acks_;
  FlowControl& flow = acq.flow;
  const auto& events = campaign.events();
  for (size_t i = 0; i < events.size(); ++i)
    if (events[i].seq != int64_t(i))
      throw InputError("campaign status event " + std::to_string(i) + " has seq " +
                       std::to_string(events[i].seq) + " (the status stream needs 0, 1, ...)");

  auto publish_status = [&](const StatusEvent& e) {
    excitation_status_t m = to_status_msg(e);
    data.publish(kStatusChannel, &m);
  };
  auto publish_command = [&](int64_t b) {
    command_block_t m =
        to_command_msg(command_block(campaign, b, o.block, o.sample_rate_hz, o_.run_id));
    data.publish(kCmdChannel, &m);
  };
  // Stops the excitation: an "abort" status and a block commanding every actuator to its
  // operating point, both with seq -1 (outside the run's sequences, so a resumed run continues the
  // same numbering; readers take neither for part of the campaign).
  int64_t next_block = 0;
  auto abort_run = [&]() {
    const int64_t at = next_block * o.block;
    StatusEvent e = events.front();
    e.state = RunState::kAbort;
    e.seq = -1;
    e.sample = at;
    e.n_samples = 0;
    e.message = "stopped by a signal";
    const command_block_t m =
        to_command_msg(abort_block(campaign, -1, at, o.block, o.sample_rate_hz, o_.run_id));
    for (int i = 0; i < 3; ++i) {
      publish_status(e);
      data.publish(kCmdChannel, &m);
    }
    throw InputError("stopped by a signal at sample " + std::to_string(at) +
                     ": the excitation is stopped and every actuator commanded back to its "
                     "operating point");
  };
  // Handles what arrived, retransmits what a consumer lacks, and fails on a stalled stream.
  auto pump = [&](int poll_ms) {
    if (o_.stop_requested && o_.stop_requested()) abort_run();
    handle_either(data_, control_, poll_ms);
    if (!acq.error.empty()) throw InputError(acq.error);
    const double now = acq.now();
    for (Stream s : {Stream::kCommand, Stream::kTape, Stream::kStatus}) {
      if (auto r = flow.due(s, now)) {
        if (s == Stream::kCommand)
          for (int64_t b = r->from; b <= r->to; ++b) publish_command(b);
        else if (s == Stream::kStatus)
          for (int64_t k = r->from; k <= r->to; ++k) publish_status(events[size_t(k)]);
        else
          publish_flow(data_, o_.run_id, "resend", "tape", r->from, r->to);
      }
      const std::string why = flow.stalled(s, now);
      if (!why.empty()) throw InputError(why);
    }
  };
  // Waits until `ok()`; the streams are pumped meanwhile.
  auto wait_until = [&](const std::function<bool()>& ok) {
    while (!ok()) pump(10);
  };

  if (o_.first_block < 0 || o_.first_block > command_block_count(campaign, o.block) ||
      o_.first_status < 0 || o_.first_status > int64_t(events.size()))
    throw InputError("resume point block " + std::to_string(o_.first_block) + ", status " +
                     std::to_string(o_.first_status) + " is outside the campaign");
  flow.begin_at(o_.first_block, o_.first_status);
  const double t_ready = acq.now();
  std::string missing;
  while (!flow.all_ready(&missing)) {
    if (o_.stop_requested && o_.stop_requested())
      throw InputError("stopped by a signal before the run started");
    handle_either(data_, control_, 50);
    if (!acq.error.empty()) throw InputError(acq.error);
    if (acq.now() - t_ready > o_.ready_timeout_s)
      throw InputError("consumer \"" + missing + "\" never said ready within " +
                       std::to_string(o_.ready_timeout_s) +
                       " s (is it running on the same LCM URL?)");
  }
  StatusEvent start = events.front();
  start.state = RunState::kStart;
  start.seq = -1;
  start.sample = 0;
  start.n_samples = campaign.total_samples();
  publish_status(start);  // outside the flow control: informative

  const auto t0 = Clock::now();
  const int64_t total = campaign.total_samples();
  const int64_t nblocks = command_block_count(campaign, o.block);
  size_t ev = size_t(o_.first_status);
  next_block = o_.first_block;
  for (int64_t b = o_.first_block; b < nblocks; ++b) {
    const Block blk = command_block(campaign, b, o.block, o.sample_rate_hz, o_.run_id);
    wait_until([&] {
      return flow.acked(Stream::kCommand) >= b - o.window &&
             flow.acked(Stream::kTape) >= b - o.window;
    });
    if (o.speed > 0) {
      auto due =
          t0 + std::chrono::duration<double>(double(blk.start_sample) / o.sample_rate_hz / o.speed);
      while (Clock::now() < due)
        pump(1 + int(std::chrono::duration<double, std::milli>(due - Clock::now()).count()));
    }
    // The block's status events, held by every consumer before the block goes out: a window's
    // definition always precedes its samples, however datagrams are lost.
    bool new_status = false;
    while (ev < events.size() &&
           (events[ev].sample < blk.start_sample + blk.n_samples || blk.final_block)) {
      publish_status(events[ev]);
      flow.published(Stream::kStatus, events[ev].seq);
      ++ev;
      new_status = true;
    }
    if (new_status)
      wait_until([&] { return flow.acked(Stream::kStatus) >= flow.available(Stream::kStatus); });
    command_block_t m = to_command_msg(blk);
    data.publish(kCmdChannel, &m);
    flow.published(Stream::kCommand, b);
    next_block = b + 1;
  }
  // Everyone holds everything: the run is judged by what was measured.
  wait_until([&] {
    return flow.acked(Stream::kCommand) >= nblocks - 1 &&
           flow.acked(Stream::kTape) >= nblocks - 1 &&
           flow.acked(Stream::kStatus) >= flow.available(Stream::kStatus);
  });
  for (int i = 0; i < 3; ++i) publish_flow(data_, o_.run_id, "close", "", 0, nblocks - 1);
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  // Engine time of this run (a resumed run: from its first block on).
  const double engine_s =
      double(total - std::min(total, o_.first_block * int64_t(o.block))) / o.sample_rate_hz;
  Json sj{{"run_id", o_.run_id},
          {"engine_time_s", engine_s},
          {"wall_time_s", wall},
          {"speedup", engine_s / std::max(wall, 1e-9)},
          {"blocks", nblocks},
          {"first_block", o_.first_block},
          {"samples", total},
          {"excitation", to_string(campaign.events().front().excitation)},
          {"retransmissions", flow.retransmissions()},
          {"items_retransmitted", flow.items_retransmitted()}};
  return sj;
}

}  // namespace fralab
