// The acquisition's flow control and retransmission logic, free of LCM and of the clock (times are
// passed in, seconds on any monotonic clock), so it is tested without a network.
//
// Three sequence-numbered streams, each acknowledged cumulatively (ack = the last seq a consumer
// holds without a gap; a duplicate is acknowledged again):
//   command: command blocks 0..n-1, acknowledged by the plant ("plant");
//   tape:    tape blocks 0..n-1, made by the plant (tape block b exists once the plant has
//            acknowledged command b), acknowledged by every other consumer (analysers, recorder);
//   status:  excitation status events 0, 1, ... (the start event, seq -1, is outside the flow
//            control), acknowledged by the same consumers.
// A stream whose slowest acknowledgement lags what exists and has not moved for
// `retransmit_after_s` is retransmitted from the first unacknowledged seq to the last that exists;
// the wait doubles after each retransmission without progress, up to `retransmit_max_s`, and is
// reset by progress. A stream that has not moved for `stall_timeout_s` is stalled: the message
// names the consumer, what it holds, what was sent and how often, and when it was last heard.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace fralab {

enum class Stream { kCommand, kTape, kStatus };
std::string to_string(Stream s);
/// "command", "tape", "status"; nullopt for any other word (e.g. "ready", "frd:...").
std::optional<Stream> stream_from_string(const std::string& s);

struct FlowOptions {
  double retransmit_after_s = 0.05;  // first retransmission of a stream that does not move
  double retransmit_max_s = 1.0;     // the doubling wait's cap
  double stall_timeout_s = 60;       // a stream that has not moved this long fails the run
  /// InputError naming the option for non-positive or inconsistent values.
  void validate() const;
};

class FlowControl {
 public:
  /// `consumers`: "plant" acknowledges the command stream, every other name the tape and status
  /// streams. "plant" is added when missing.
  FlowControl(std::vector<std::string> consumers, FlowOptions o = {});

  /// Resume: the streams start at command/tape block `first_block` and status event
  /// `first_status` (everything before is held already): a consumer that said ready holds
  /// first - 1.
  void begin_at(int64_t first_block, int64_t first_status);
  /// An acknowledgement: stream "ready" (subscribed), "command", "tape" or "status"; other streams
  /// and unknown consumers are ignored. Later acknowledgements never move a consumer back.
  void on_ack(const std::string& consumer, const std::string& stream, int64_t seq, double now);
  /// Every consumer has said ready (or acknowledged anything); otherwise *missing names one.
  bool all_ready(std::string* missing) const;
  /// The acquisition has published `seq` on `s` (command blocks, status events); with a
  /// free-running plant, the tape blocks it has seen the plant make.
  void published(Stream s, int64_t seq);
  /// A free-running plant: tape blocks are made by the plant's clock, not one per
  /// command, so what exists on the tape is what published(kTape, ..) reported, not the plant's
  /// command acknowledgement.
  void tape_on_plant_clock() { tape_on_plant_clock_ = true; }
  /// The last seq that exists on `s`: the last published command or status event; for the tape,
  /// the plant's command acknowledgement (-1 before any), or with tape_on_plant_clock() the last
  /// tape block published.
  int64_t available(Stream s) const;
  /// The lowest acknowledgement on `s` among its consumers (-1 for one that said ready and
  /// nothing more on `s`, -2 for one never heard);
  /// *laggard names that consumer.
  int64_t acked(Stream s, std::string* laggard = nullptr) const;

  struct Resend {
    Stream stream;
    int64_t from, to;  // inclusive
  };
  /// The retransmission due on `s` now, if any (see the file comment); counts it.
  std::optional<Resend> due(Stream s, double now);
  /// "" while `s` moves; else why it stalled (see the file comment).
  std::string stalled(Stream s, double now) const;
  /// Retransmissions so far on all streams, and items (blocks or events) retransmitted.
  int64_t retransmissions() const { return resends_; }
  int64_t items_retransmitted() const { return items_resent_; }

 private:
  struct State {
    int64_t published = -1;  // nothing yet
    int64_t last_min = -3;
    double t_progress = 0;  // last time the slowest acknowledgement moved or caught up
    double t_resend = -1e300;
    double wait = 0;
    int64_t resends_since_progress = 0;
  };
  std::vector<std::string> of(Stream s) const;
  State& st(Stream s) { return state_[int(s)]; }
  const State& st(Stream s) const { return state_[int(s)]; }

  std::vector<std::string> consumers_;
  FlowOptions o_;
  std::map<std::string, std::map<std::string, int64_t>> acked_;  // consumer -> stream -> seq
  std::map<std::string, double> heard_;                          // consumer -> last time heard
  State state_[3];
  int64_t floor_[3] = {-1, -1, -1};  // what a ready consumer holds (begin_at)
  int64_t resends_ = 0, items_resent_ = 0;
  bool tape_on_plant_clock_ = false;
};

}  // namespace fralab
