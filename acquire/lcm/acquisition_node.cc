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
  require_sized_block(o_.acquire.block, "acquisition");
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

// One run of the campaign: the steps of run(), sharing the node's transport, flow control and
// tape watch.
class AcquisitionNode::Run {
 public:
  explicit Run(AcquisitionNode& n)
      : n_(n),
        o_(n.o_),
        a_(n.o_.acquire),
        campaign_(n.campaign_),
        events_(n.campaign_.events()),
        acks_(*n.acks_),
        flow_(n.acks_->flow),
        tape_(n.tape_.get()),
        nblocks_(command_block_count(n.campaign_, n.o_.acquire.block)),
        lead_samples_(int64_t(n.o_.acquire.lead) * n.o_.acquire.block) {}

  AcquisitionSummary operator()() {
    check_campaign_and_resume_point();
    wait_for_consumers();
    publish_start();
    t0_ = Clock::now();
    send_campaign();
    if (a_.free_running) play_out_and_repeat();
    wait_until_everyone_holds_everything();
    for (int i = 0; i < 3; ++i) publish_flow(n_.data_, o_.run_id, "close", "", 0, last_command_);
    return summary();
  }

 private:
  void check_campaign_and_resume_point() const {
    for (size_t i = 0; i < events_.size(); ++i)
      if (events_[i].seq != int64_t(i))
        throw InputError("campaign status event " + std::to_string(i) + " has seq " +
                         std::to_string(events_[i].seq) + " (the status stream needs 0, 1, ...)");
    if (o_.first_block < 0 || o_.first_block > nblocks_ || o_.first_status < 0 ||
        o_.first_status > int64_t(events_.size()))
      throw InputError("resume point block " + std::to_string(o_.first_block) + ", status " +
                       std::to_string(o_.first_status) + " is outside the campaign");
  }

  void publish_status(const StatusEvent& e) {
    excitation_status_t m = to_status_msg(e);
    n_.data_.publish(kStatusChannel, &m);
  }

  // Free-running, the command blocks from the campaign's last on (its final flag cleared, the
  // play-out's idle blocks, the repeated steps) are not the campaign's blocks of their seq: kept
  // as published, so that a retransmission sends them again as they were.
  void publish_command(int64_t b) {
    if (const auto it = sent_free_.find(b); it != sent_free_.end()) {
      n_.data_.publish(kCmdChannel, &it->second);
      return;
    }
    command_block_t m =
        to_command_msg(command_block(campaign_, b, a_.block, a_.sample_rate_hz, o_.run_id));
    n_.data_.publish(kCmdChannel, &m);
  }

  // Stops the excitation: an "abort" status and a block commanding every actuator to its
  // operating point, both with seq -1 (outside the run's sequences, so a resumed run continues
  // the same numbering; readers take neither for part of the campaign).
  [[noreturn]] void abort_run() {
    const int64_t at = next_block_ * a_.block;
    StatusEvent e = events_.front();
    e.state = RunState::kAbort;
    e.seq = -1;
    e.sample = at;
    e.n_samples = 0;
    e.message = "stopped by a signal";
    const command_block_t m =
        to_command_msg(abort_block(campaign_, -1, at, a_.block, a_.sample_rate_hz, o_.run_id));
    for (int i = 0; i < 3; ++i) {
      publish_status(e);
      n_.data_.publish(kCmdChannel, &m);
    }
    throw InputError("stopped by a signal at sample " + std::to_string(at) +
                     ": the excitation is stopped and every actuator commanded back to its "
                     "operating point");
  }

  // Handles what arrived, retransmits what a consumer lacks, and fails on a stalled stream.
  void pump(int poll_ms) {
    if (o_.stop_requested && o_.stop_requested()) abort_run();
    handle_either(n_.data_, n_.control_, poll_ms);
    if (!acks_.error.empty()) throw InputError(acks_.error);
    if (tape_ && !tape_->error.empty()) throw InputError(tape_->error);
    const double now = acks_.now();
    if (a_.free_running && tape_->last_seq >= 0) flow_.published(Stream::kTape, tape_->last_seq);
    for (Stream s : {Stream::kCommand, Stream::kTape, Stream::kStatus}) {
      if (auto r = flow_.due(s, now)) {
        if (s == Stream::kCommand)
          for (int64_t b = r->from; b <= r->to; ++b) publish_command(b);
        else if (s == Stream::kStatus)
          for (int64_t k = r->from; k <= r->to; ++k) publish_status(events_[size_t(k)]);
        else
          publish_flow(n_.data_, o_.run_id, "resend", "tape", r->from, r->to);
      }
      const std::string why = flow_.stalled(s, now);
      if (!why.empty()) throw InputError(why);
    }
  }

  // Waits until `ok()`; the streams are pumped meanwhile.
  template <class Ok>
  void wait_until(const Ok& ok) {
    while (!ok()) pump(10);
  }

  void wait_for_consumers() {
    flow_.begin_at(o_.first_block, o_.first_status);
    const double t_ready = acks_.now();
    std::string missing;
    while (!flow_.all_ready(&missing)) {
      if (o_.stop_requested && o_.stop_requested())
        throw InputError("stopped by a signal before the run started");
      handle_either(n_.data_, n_.control_, 50);
      if (!acks_.error.empty()) throw InputError(acks_.error);
      if (acks_.now() - t_ready > o_.ready_timeout_s)
        throw InputError("consumer \"" + missing + "\" never said ready within " +
                         std::to_string(o_.ready_timeout_s) +
                         " s (is it running on the same LCM URL?)");
    }
  }

  // The start event: the run's length and measurement chain, outside the flow control
  // (informative).
  void publish_start() {
    StatusEvent start = events_.front();
    start.state = RunState::kStart;
    start.seq = -1;
    start.sample = 0;
    start.n_samples = campaign_.total_samples();
    start.measurement_chain = o_.measurement_chain;
    publish_status(start);
  }

  // Adaptive: the decision pending at sample E is taken before a block starting at or after E goes
  // out (the campaign, its events and its length may change then); the tape it needs is asked for
  // again when it is slow to come.
  void decide_before(int64_t b) {
    AutoIntegrator* const ai = o_.auto_integrator;
    double t_asked = acks_.now();
    while (ai->decision_sample() >= 0 && b * a_.block >= ai->decision_sample()) {
      if (ai->decide()) continue;
      pump(5);
      const auto [from, to] = ai->needed_samples();
      int64_t lost = -1;
      for (int64_t k = from / a_.block; k <= (to - 1) / a_.block && lost < 0; ++k)
        if (!tape_->seen.count(k)) lost = k;
      if (lost >= 0 && acks_.now() - t_asked > 0.2) {
        publish_flow(n_.data_, o_.run_id, "resend", "tape", lost, (to - 1) / a_.block);
        t_asked = acks_.now();
      }
    }
  }

  // The campaign's command blocks in order, each when the flow control lets it go (lockstep: at
  // most `window` blocks ahead of the slowest consumer; free-running: at most `lead` blocks ahead
  // of the plant's clock), each preceded by the status events that take effect in it.
  void send_campaign() {
    size_t ev = size_t(o_.first_status);
    next_block_ = o_.first_block;
    const bool free = a_.free_running;
    // Free-running: the last event ("done") and the final block wait until every step is known
    // to have been played without a held sample (the play-out).
    const size_t n_done_held = free ? 1 : 0;
    for (int64_t b = o_.first_block; b < command_block_count(campaign_, a_.block); ++b) {
      if (o_.auto_integrator) decide_before(b);
      if (b >= command_block_count(campaign_, a_.block)) break;
      const size_t n_events = events_.size() - n_done_held;
      Block blk = command_block(campaign_, b, a_.block, a_.sample_rate_hz, o_.run_id);
      if (free) {  // ahead of the plant's clock by at most `lead` blocks; the plant does not wait
        blk.final_block = false;
        wait_until([&] { return blk.start_sample - tape_->played < lead_samples_; });
      } else {
        wait_until([&] {
          return flow_.acked(Stream::kCommand) >= b - a_.window &&
                 flow_.acked(Stream::kTape) >= b - a_.window;
        });
      }
      if (a_.speed > 0 && !free) {
        auto due = t0_ + std::chrono::duration<double>(double(blk.start_sample) /
                                                       a_.sample_rate_hz / a_.speed);
        while (Clock::now() < due)
          pump(1 + int(std::chrono::duration<double, std::milli>(due - Clock::now()).count()));
      }
      // The block's status events, held by every consumer before the block goes out: a window's
      // definition always precedes its samples, however datagrams are lost.
      bool new_status = false;
      while (ev < n_events &&
             (events_[ev].sample < blk.start_sample + blk.n_samples || blk.final_block)) {
        publish_status(events_[ev]);
        flow_.published(Stream::kStatus, events_[ev].seq);
        ++ev;
        new_status = true;
      }
      if (new_status)
        wait_until(
            [&] { return flow_.acked(Stream::kStatus) >= flow_.available(Stream::kStatus); });
      command_block_t m = to_command_msg(blk);
      if (free && b == command_block_count(campaign_, a_.block) - 1) sent_free_[b] = m;
      n_.data_.publish(kCmdChannel, &m);
      flow_.published(Stream::kCommand, b);
      next_block_ = b + 1;
    }
    nblocks_ = command_block_count(campaign_, a_.block);
    last_command_ = last_tape_ = nblocks_ - 1;
  }

  // Free-running: a command block `lead` blocks ahead of the plant's clock at most, kept as sent.
  void publish_free_block(Block c) {
    c.seq = cmd_seq_++;
    wait_until([&] { return c.start_sample - tape_->played < lead_samples_; });
    command_block_t m = to_command_msg(c);
    sent_free_[c.seq] = m;
    n_.data_.publish(kCmdChannel, &m);
    flow_.published(Stream::kCommand, c.seq);
  }

  // Free-running: every actuator at its operating point for a block.
  void idle_block(bool final) {
    Block c = abort_block(campaign_, 0, pos_, a_.block, a_.sample_rate_hz, o_.run_id);
    c.final_block = final;
    publish_free_block(c);
    pos_ += a_.block;
  }

  // Free-running: a status event beyond the campaign's, held by every consumer before going on.
  void publish_free_event(const StatusEvent& e) {
    publish_status(e);
    flow_.published(Stream::kStatus, e.seq);
    wait_until([&] { return flow_.acked(Stream::kStatus) >= flow_.available(Stream::kStatus); });
  }

  // Free-running: idle blocks keep the plant fed until it has played (and the acquisition seen,
  // without a gap) everything commanded so far.
  void play_out() {
    const int64_t target = pos_;
    while (!(tape_->played >= target && tape_->contiguous() == tape_->last_seq)) {
      if (pos_ - tape_->played < lead_samples_) {
        idle_block(false);
        continue;
      }
      pump(5);
      const int64_t c = tape_->contiguous();
      if (c < tape_->last_seq && acks_.now() - t_asked_ > 0.2) {  // lost on the way here
        publish_flow(n_.data_, o_.run_id, "resend", "tape", c + 1, tape_->last_seq);
        t_asked_ = acks_.now();
      }
    }
  }

  // Free-running: play out, look at the tape for held samples in any step, repeat those steps at
  // the end, until none is touched; then "done" and the final block.
  void play_out_and_repeat() {
    pos_ = campaign_.total_samples();
    cmd_seq_ = nblocks_;
    int64_t status_seq = events_.back().seq;
    // Each step's span (settle and integrate) and its integrate event, latest run of it.
    std::map<int, std::pair<int64_t, int64_t>> span;
    std::map<int, StatusEvent> integ;
    int64_t settle_at = 0;
    for (const auto& e : events_) {
      if (e.state == RunState::kSettle) settle_at = e.sample;
      if (e.state != RunState::kIntegrate) continue;
      span[e.step] = {std::min(settle_at, e.sample), e.sample + e.n_samples};
      integ[e.step] = e;
    }
    for (int round = 0;; ++round) {
      play_out();
      std::vector<int> hit;
      for (const auto& [step, sp] : span)
        if (tape_->held.within(sp.first, sp.second)) hit.push_back(step);
      if (hit.empty()) break;
      if (round >= a_.max_repeats)
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
        const SteppedSineCampaign rep(campaign_.inputs(), {input}, {s}, a_.sample_rate_hz,
                                      o_.run_id);
        const int64_t start = pos_;
        for (StatusEvent x : rep.events()) {
          if (x.state != RunState::kSettle && x.state != RunState::kIntegrate) continue;
          x.sample += start;
          x.seq = status_seq++;
          x.step = e.step;
          x.n_steps = e.n_steps;
          if (x.state == RunState::kIntegrate) integ[step] = x;
          publish_free_event(x);
        }
        for (int64_t k = 0; k < command_block_count(rep, a_.block); ++k) {
          Block c = command_block(rep, k, a_.block, a_.sample_rate_hz, o_.run_id);
          c.start_sample += start;
          c.final_block = false;
          publish_free_block(c);
        }
        pos_ = start + rep.total_samples();
        span[step] = {start, pos_};
        repeats_.push_back({step, e.frequency_hz, round + 1});
      }
    }
    StatusEvent done = events_.back();
    done.seq = status_seq;
    done.sample = pos_;
    publish_free_event(done);
    idle_block(true);
    last_command_ = cmd_seq_ - 1;
    wait_until([&] { return tape_->final_seq >= 0; });
    last_tape_ = tape_->final_seq;
  }

  // Everyone holds everything: the run is judged by what was measured.
  void wait_until_everyone_holds_everything() {
    wait_until([&] {
      return flow_.acked(Stream::kCommand) >= last_command_ &&
             flow_.acked(Stream::kTape) >= last_tape_ &&
             flow_.acked(Stream::kStatus) >= flow_.available(Stream::kStatus);
    });
  }

  AcquisitionSummary summary() const {
    const double wall = std::chrono::duration<double>(Clock::now() - t0_).count();
    const int64_t total = campaign_.total_samples();
    AcquisitionSummary s;
    s.run_id = o_.run_id;
    // Engine time of this run (a resumed run: from its first block on).
    s.engine_time_s =
        double(total - std::min(total, o_.first_block * int64_t(a_.block))) / a_.sample_rate_hz;
    s.wall_time_s = wall;
    s.blocks = nblocks_;
    s.first_block = o_.first_block;
    s.samples = total;
    s.excitation = campaign_.events().front().excitation;
    s.retransmissions = flow_.retransmissions();
    s.items_retransmitted = flow_.items_retransmitted();
    s.free_running = a_.free_running;
    if (o_.auto_integrator) s.adaptive = adaptive_steps_json(o_.auto_integrator->results());
    if (s.free_running) {
      s.held_samples = tape_->held.count();
      s.repeated_steps = repeats_;
      s.engine_time_s = double(tape_->played) / a_.sample_rate_hz;  // held and repeated too
    }
    s.speedup = s.engine_time_s / std::max(wall, 1e-9);
    return s;
  }

  AcquisitionNode& n_;
  const AcquisitionLoopOptions& o_;
  const AcquireOptions& a_;
  const Campaign& campaign_;
  const std::vector<StatusEvent>& events_;
  Acks& acks_;
  FlowControl& flow_;
  TapeWatch* tape_;
  int64_t nblocks_;
  const int64_t lead_samples_;
  Clock::time_point t0_ = Clock::now();
  int64_t next_block_ = 0;                        // the next command block (an abort's sample)
  std::map<int64_t, command_block_t> sent_free_;  // free-running: blocks kept as sent
  int64_t last_command_ = -1, last_tape_ = -1;    // what every consumer must hold at the end
  int64_t pos_ = 0, cmd_seq_ = 0;                 // free-running play-out: next sample, next seq
  double t_asked_ = -1;                           // free-running: the last resend asked for
  std::vector<RepeatedStep> repeats_;
};

AcquisitionSummary AcquisitionNode::run() { return Run(*this)(); }

}  // namespace fralab
