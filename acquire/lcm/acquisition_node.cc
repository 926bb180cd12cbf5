#include "acquisition_node.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <map>
#include <set>

#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/lab_lcm.h"

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

// A free-running plant's tape, as the acquisition watches it: how far the plant's clock has
// played, which tape blocks exist, and the samples it held (its command buffer ran dry).
struct AcquisitionNode::TapeWatch {
  std::string run_id;
  int64_t played = 0;      // samples played: the end of the furthest tape block seen
  int64_t last_seq = -1;   // the furthest tape block seen
  int64_t final_seq = -1;  // the plant's final tape block, once seen
  std::set<int64_t> seen;  // tape seqs seen
  HeldSamples held;        // samples the plant held
  AutoIntegrator* integrator = nullptr;
  std::string error;  // the integrator refused a block (a corrupt record)
  void on_tape(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    Block b;
    try {
      b = decode_tape_block(rbuf, ch);
    } catch (const std::exception&) {
      return;  // corrupt or foreign: the consumers ask for it again
    }
    if (b.run_id != run_id || b.seq < 0 || !seen.insert(b.seq).second) return;
    while (seen.count(contiguous_ + 1)) ++contiguous_;
    played = std::max(played, b.start_sample + b.n_samples);
    last_seq = std::max(last_seq, b.seq);
    if (b.final_block) final_seq = b.seq;
    held.add(b);
    if (integrator) {
      try {
        integrator->on_block(b);
      } catch (const std::exception& e) {
        error = std::string("adaptive stepped sine: ") + e.what();
      }
    }
  }
  /// The last tape block up to which every one was seen (none lost on the way here).
  int64_t contiguous() const { return contiguous_; }
  int64_t contiguous_ = -1;
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
  if (o_.acquire.free_running || o_.auto_integrator) {
    tape_ = std::make_unique<TapeWatch>();
    tape_->run_id = o_.run_id;
    tape_->integrator = o_.auto_integrator;
    tape_sub_ = data_.subscribe(kTapeChannel, &TapeWatch::on_tape, tape_.get());
    tape_sub_->setQueueCapacity(100000);
  }
  if (o_.acquire.free_running) acks_->flow.tape_on_plant_clock();
}

AcquisitionNode::~AcquisitionNode() {
  control_.unsubscribe(sub_);
  if (tape_sub_) data_.unsubscribe(tape_sub_);
}

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
  // Free-running, the command blocks from the campaign's last on (its final flag cleared, the
  // play-out's idle blocks, the repeated steps) are not the campaign's blocks of their seq: kept as
  // published, so that a retransmission sends them again as they were.
  std::map<int64_t, command_block_t> sent_free;
  auto publish_command = [&](int64_t b) {
    if (const auto it = sent_free.find(b); it != sent_free.end()) {
      data.publish(kCmdChannel, &it->second);
      return;
    }
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
    if (tape_ && !tape_->error.empty()) throw InputError(tape_->error);
    const double now = acq.now();
    if (o.free_running && tape_->last_seq >= 0) flow.published(Stream::kTape, tape_->last_seq);
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
  start.measurement_chain = o_.measurement_chain;
  publish_status(start);  // outside the flow control: informative

  const auto t0 = Clock::now();
  size_t ev = size_t(o_.first_status);
  next_block = o_.first_block;
  const bool free = o.free_running;
  // Free-running: the last event ("done") and the final block wait until every step is known to
  // have been played without a held sample (the play-out after this loop).
  const size_t n_done_held = free ? 1 : 0;
  const int64_t lead_samples = int64_t(o.lead) * o.block;
  AutoIntegrator* const ai = o_.auto_integrator;
  // Adaptive: the decision pending at sample E is taken before a block starting at or after E goes
  // out (the campaign, its events and its length may change then); the tape it needs is asked for
  // again when it is slow to come.
  auto decide_before = [&](int64_t b) {
    double t_asked = acq.now();
    while (ai->decision_sample() >= 0 && b * o.block >= ai->decision_sample()) {
      if (ai->decide()) continue;
      pump(5);
      const auto [from, to] = ai->needed_samples();
      int64_t lost = -1;
      for (int64_t k = from / o.block; k <= (to - 1) / o.block && lost < 0; ++k)
        if (!tape_->seen.count(k)) lost = k;
      if (lost >= 0 && acq.now() - t_asked > 0.2) {
        publish_flow(data_, o_.run_id, "resend", "tape", lost, (to - 1) / o.block);
        t_asked = acq.now();
      }
    }
  };
  for (int64_t b = o_.first_block; b < command_block_count(campaign, o.block); ++b) {
    if (ai) decide_before(b);
    if (b >= command_block_count(campaign, o.block)) break;
    const size_t n_events = events.size() - n_done_held;
    Block blk = command_block(campaign, b, o.block, o.sample_rate_hz, o_.run_id);
    if (free) {  // ahead of the plant's clock by at most `lead` blocks; the plant does not wait
      blk.final_block = false;
      wait_until([&] { return blk.start_sample - tape_->played < lead_samples; });
    } else {
      wait_until([&] {
        return flow.acked(Stream::kCommand) >= b - o.window &&
               flow.acked(Stream::kTape) >= b - o.window;
      });
    }
    if (o.speed > 0 && !free) {
      auto due =
          t0 + std::chrono::duration<double>(double(blk.start_sample) / o.sample_rate_hz / o.speed);
      while (Clock::now() < due)
        pump(1 + int(std::chrono::duration<double, std::milli>(due - Clock::now()).count()));
    }
    // The block's status events, held by every consumer before the block goes out: a window's
    // definition always precedes its samples, however datagrams are lost.
    bool new_status = false;
    while (ev < n_events &&
           (events[ev].sample < blk.start_sample + blk.n_samples || blk.final_block)) {
      publish_status(events[ev]);
      flow.published(Stream::kStatus, events[ev].seq);
      ++ev;
      new_status = true;
    }
    if (new_status)
      wait_until([&] { return flow.acked(Stream::kStatus) >= flow.available(Stream::kStatus); });
    command_block_t m = to_command_msg(blk);
    if (free && b == command_block_count(campaign, o.block) - 1) sent_free[b] = m;
    data.publish(kCmdChannel, &m);
    flow.published(Stream::kCommand, b);
    next_block = b + 1;
  }
  const int64_t total = campaign.total_samples();
  const int64_t nblocks = command_block_count(campaign, o.block);
  int64_t last_command = nblocks - 1, last_tape = nblocks - 1;
  Json repeats = Json::array();
  if (free) {
    // Play out, look at the tape for held samples in any step, repeat those steps at the end,
    // until none is touched; then "done" and the final block.
    int64_t pos = total, cmd_seq = nblocks, status_seq = events.back().seq;
    auto publish_block = [&](Block c) {
      c.seq = cmd_seq++;
      wait_until([&] { return c.start_sample - tape_->played < lead_samples; });
      command_block_t m = to_command_msg(c);
      sent_free[c.seq] = m;
      data.publish(kCmdChannel, &m);
      flow.published(Stream::kCommand, c.seq);
    };
    auto idle_block = [&](bool final) {
      Block c = abort_block(campaign, 0, pos, o.block, o.sample_rate_hz, o_.run_id);
      c.final_block = final;
      publish_block(c);
      pos += o.block;
    };
    auto publish_event = [&](const StatusEvent& e) {
      publish_status(e);
      flow.published(Stream::kStatus, e.seq);
      wait_until([&] { return flow.acked(Stream::kStatus) >= flow.available(Stream::kStatus); });
    };
    // Each step's span (settle and integrate) and its integrate event, latest run of it.
    std::map<int, std::pair<int64_t, int64_t>> span;
    std::map<int, StatusEvent> integ;
    int64_t settle_at = 0;
    for (const auto& e : events) {
      if (e.state == RunState::kSettle) settle_at = e.sample;
      if (e.state != RunState::kIntegrate) continue;
      span[e.step] = {std::min(settle_at, e.sample), e.sample + e.n_samples};
      integ[e.step] = e;
    }
    double t_asked = -1;
    for (int round = 0;; ++round) {
      // Idle blocks keep the plant fed until it has played (and the acquisition seen, without a
      // gap) everything commanded so far.
      const int64_t target = pos;
      while (!(tape_->played >= target && tape_->contiguous() == tape_->last_seq)) {
        if (pos - tape_->played < lead_samples) {
          idle_block(false);
          continue;
        }
        pump(5);
        const int64_t c = tape_->contiguous();
        if (c < tape_->last_seq && acq.now() - t_asked > 0.2) {  // lost on the way here
          publish_flow(data_, o_.run_id, "resend", "tape", c + 1, tape_->last_seq);
          t_asked = acq.now();
        }
      }
      std::vector<int> hit;
      for (const auto& [step, sp] : span)
        if (tape_->held.within(sp.first, sp.second)) hit.push_back(step);
      if (hit.empty()) break;
      if (round >= o.max_repeats)
        throw InputError(
            "the free-running plant's command buffer ran dry in " + std::to_string(hit.size()) +
            " steps again after " + std::to_string(round) +
            " rounds of repeats (held samples: " + std::to_string(tape_->held.count()) +
            "): the commands do not reach the plant in time; lower --speed or raise --lead");
      for (int step : hit) {
        const StatusEvent e = integ[step];  // a copy: integ[step] becomes the repeat's below
        int input = -1;
        for (size_t i = 0; i < e.amplitudes.size(); ++i)
          if (e.amplitudes[i] > 0 && input < 0) input = int(i);
        SineStep s;
        s.f_hz = e.frequency_hz;
        s.n_cycles = e.n_cycles;
        s.integrate_samples = e.n_samples;
        s.settle_samples = span[step].second - span[step].first - e.n_samples;
        const SteppedSineCampaign rep(campaign.inputs(), {input}, {s}, o.sample_rate_hz, o_.run_id);
        const int64_t start = pos;
        for (StatusEvent x : rep.events()) {
          if (x.state != RunState::kSettle && x.state != RunState::kIntegrate) continue;
          x.sample += start;
          x.seq = status_seq++;
          x.step = e.step;
          x.n_steps = e.n_steps;
          if (x.state == RunState::kIntegrate) integ[step] = x;
          publish_event(x);
        }
        for (int64_t k = 0; k < command_block_count(rep, o.block); ++k) {
          Block c = command_block(rep, k, o.block, o.sample_rate_hz, o_.run_id);
          c.start_sample += start;
          c.final_block = false;
          publish_block(c);
        }
        pos = start + rep.total_samples();
        span[step] = {start, pos};
        repeats.push_back({{"step", step}, {"frequency_hz", e.frequency_hz}, {"round", round + 1}});
      }
    }
    StatusEvent done = events.back();
    done.seq = status_seq;
    done.sample = pos;
    publish_event(done);
    idle_block(true);
    last_command = cmd_seq - 1;
    wait_until([&] { return tape_->final_seq >= 0; });
    last_tape = tape_->final_seq;
  }
  // Everyone holds everything: the run is judged by what was measured.
  wait_until([&] {
    return flow.acked(Stream::kCommand) >= last_command && flow.acked(Stream::kTape) >= last_tape &&
           flow.acked(Stream::kStatus) >= flow.available(Stream::kStatus);
  });
  for (int i = 0; i < 3; ++i) publish_flow(data_, o_.run_id, "close", "", 0, last_command);
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
          {"items_retransmitted", flow.items_retransmitted()},
          {"plant_clock", free ? "free" : "lockstep"}};
  if (ai) sj["adaptive"] = adaptive_steps_json(ai->results());
  if (free) {
    sj["held_samples"] = tape_->held.count();
    sj["repeated_steps"] = repeats;
    sj["engine_time_s"] = double(tape_->played) / o.sample_rate_hz;  // held and repeated included
    sj["speedup"] = sj["engine_time_s"].get<double>() / std::max(wall, 1e-9);
  }
  return sj;
}

}  // namespace fralab
