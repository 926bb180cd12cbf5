#include "fralab/acquire/flow_control.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "fralab/core/error.h"

namespace fralab {

std::string to_string(Stream s) {
  switch (s) {
    case Stream::kCommand:
      return "command";
    case Stream::kTape:
      return "tape";
    case Stream::kStatus:
      return "status";
  }
  return "?";
}

std::optional<Stream> stream_from_string(const std::string& s) {
  for (Stream k : {Stream::kCommand, Stream::kTape, Stream::kStatus})
    if (to_string(k) == s) return k;
  return std::nullopt;
}

void FlowOptions::validate() const {
  if (!(retransmit_after_s > 0)) throw InputError("flow control: retransmit_after_s must be > 0");
  if (!(retransmit_max_s >= retransmit_after_s))
    throw InputError("flow control: retransmit_max_s must be >= retransmit_after_s");
  if (!(stall_timeout_s > retransmit_max_s))
    throw InputError("flow control: stall_timeout_s must exceed retransmit_max_s");
}

FlowControl::FlowControl(std::vector<std::string> consumers, FlowOptions o)
    : consumers_(std::move(consumers)), o_(o) {
  o_.validate();
  if (std::find(consumers_.begin(), consumers_.end(), "plant") == consumers_.end())
    consumers_.push_back("plant");
  for (auto& s : state_) s.wait = o_.retransmit_after_s;
}

std::vector<std::string> FlowControl::of(Stream s) const {
  std::vector<std::string> who;
  for (const auto& c : consumers_)
    if ((c == "plant") == (s == Stream::kCommand)) who.push_back(c);
  return who;
}

void FlowControl::begin_at(int64_t first_block, int64_t first_status) {
  floor_[int(Stream::kCommand)] = floor_[int(Stream::kTape)] = first_block - 1;
  floor_[int(Stream::kStatus)] = first_status - 1;
  st(Stream::kCommand).published = first_block - 1;
  st(Stream::kStatus).published = first_status - 1;
}

void FlowControl::on_ack(const std::string& consumer, const std::string& stream, int64_t seq,
                         double now) {
  if (std::find(consumers_.begin(), consumers_.end(), consumer) == consumers_.end()) return;
  heard_[consumer] = now;
  auto& a = acked_[consumer];
  auto it = a.find(stream);
  if (it == a.end())
    a[stream] = seq;
  else
    it->second = std::max(it->second, seq);
}

bool FlowControl::all_ready(std::string* missing) const {
  for (const auto& c : consumers_) {
    if (!heard_.count(c)) {
      if (missing) *missing = c;
      return false;
    }
  }
  return true;
}

void FlowControl::published(Stream s, int64_t seq) {
  State& t = st(s);
  t.published = std::max(t.published, seq);
}

int64_t FlowControl::available(Stream s) const {
  if (s == Stream::kTape && !tape_on_plant_clock_)
    return std::max<int64_t>(acked(Stream::kCommand), floor_[int(Stream::kTape)]);
  return st(s).published;
}

int64_t FlowControl::acked(Stream s, std::string* laggard) const {
  int64_t m = INT64_MAX;
  const std::string key = to_string(s);
  for (const auto& c : of(s)) {
    int64_t v = heard_.count(c) ? floor_[int(s)] : -2;  // ready, nothing on this stream yet
    auto ic = acked_.find(c);
    if (ic != acked_.end()) {
      auto is = ic->second.find(key);
      if (is != ic->second.end()) v = is->second;
    }
    if (heard_.count(c)) v = std::max(v, floor_[int(s)]);
    if (v < m) {
      m = v;
      if (laggard) *laggard = c;
    }
  }
  return m == INT64_MAX ? available(s) : m;
}

std::optional<FlowControl::Resend> FlowControl::due(Stream s, double now) {
  State& t = st(s);
  const int64_t lo = acked(s), av = available(s);
  if (lo != t.last_min || lo >= av || av < 0) {  // progress, or nothing outstanding
    t.last_min = lo;
    t.t_progress = now;
    t.wait = o_.retransmit_after_s;
    t.resends_since_progress = 0;
    return std::nullopt;
  }
  if (now - std::max(t.t_progress, t.t_resend) < t.wait) return std::nullopt;
  t.t_resend = now;
  t.wait = std::min(2 * t.wait, o_.retransmit_max_s);
  ++t.resends_since_progress;
  ++resends_;
  const int64_t from = std::max<int64_t>(lo + 1, floor_[int(s)] + 1);
  items_resent_ += av - from + 1;
  return Resend{s, from, av};
}

std::string FlowControl::stalled(Stream s, double now) const {
  const State& t = st(s);
  std::string who;
  const int64_t lo = acked(s, &who), av = available(s);
  if (lo >= av || now - t.t_progress < o_.stall_timeout_s) return "";
  const std::string what = s == Stream::kStatus ? "status events" : to_string(s) + " blocks";
  std::string msg = "consumer \"" + who + "\" holds " + what + " up to " + std::to_string(lo) +
                    " and has not moved for " + std::to_string(int(now - t.t_progress)) +
                    " s, although " + what + " up to " + std::to_string(av) +
                    " exist and were retransmitted " + std::to_string(t.resends_since_progress) +
                    " times";
  auto h = heard_.find(who);
  if (h == heard_.end() || now - h->second > o_.stall_timeout_s / 2)
    msg += "; nothing heard from it for " +
           (h == heard_.end() ? std::string("the whole run")
                              : std::to_string(int(now - h->second)) + " s") +
           " (hung, stopped or dead?)";
  else
    msg += "; it answers (last heard " + std::to_string(now - h->second).substr(0, 4) +
           " s ago) but does not receive them (a network dropping its datagrams?)";
  return msg;
}

}  // namespace fralab
