#include "fralab/plant/faults.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fralab {
namespace {

struct KindName {
  ChannelFaultKind kind;
  const char* name;
};
constexpr KindName kKinds[] = {
    {ChannelFaultKind::kClock, "clock"}, {ChannelFaultKind::kHum, "hum"},
    {ChannelFaultKind::kDrift, "drift"}, {ChannelFaultKind::kClip, "clip"},
    {ChannelFaultKind::kSign, "sign"},   {ChannelFaultKind::kScale, "scale"},
    {ChannelFaultKind::kDead, "dead"},   {ChannelFaultKind::kDropouts, "dropouts"},
    {ChannelFaultKind::kSwap, "swap"},   {ChannelFaultKind::kStuck, "stuck"}};

double nonnegative(const Json& j, const JsonWhere& w, const std::string& key, double def) {
  const double v = json_number_member(j, w, key, def);
  if (v < 0.0) json_fail(w / key, key + " must be >= 0");
  return v;
}

// One fault's fields by its kind, checked (a stuck actuator only on an input).
ChannelFault channel_fault_fields(const Json& f, const JsonWhere& w, ChannelFaultKind kind,
                                  bool on_input) {
  ChannelFault c;
  c.kind = kind;
  switch (c.kind) {
    case ChannelFaultKind::kClip:
      if (f.contains("min")) c.min = json_number(f["min"], w / "min");
      if (f.contains("max")) c.max = json_number(f["max"], w / "max");
      if (!c.min && !c.max) json_fail(w, "a clip needs min, max or both (channel units)");
      if (c.min && c.max && !(*c.min < *c.max)) json_fail(w / "max", "max must exceed min");
      break;
    case ChannelFaultKind::kHum: {
      c.frequency_hz = json_number_member(f, w, "frequency_hz", 50.0);
      if (!(c.frequency_hz > 0.0)) json_fail(w / "frequency_hz", "frequency_hz must be > 0");
      c.amplitude = nonnegative(f, w, "amplitude", 0.0);
      c.phase_deg = json_number_member(f, w, "phase_deg", 0.0);
      if (f.contains("harmonics")) {
        const Json& hs = json_array_member(f, w, "harmonics");
        c.harmonics.clear();
        for (size_t m = 0; m < hs.size(); ++m) {
          const int64_t v = json_integer(hs[m], w / "harmonics" / m);
          if (v < 1 || v > 100) json_fail(w / "harmonics" / m, "a harmonic must be in 1..100");
          c.harmonics.push_back(int(v));
        }
      }
      break;
    }
    case ChannelFaultKind::kDrift:
      c.rate = json_number_member(f, w, "rate");
      c.from_s = nonnegative(f, w, "from_s", 0.0);
      break;
    case ChannelFaultKind::kSign:
      break;
    case ChannelFaultKind::kScale:
      c.factor = json_number_member(f, w, "factor");
      if (c.factor == 0.0) json_fail(w / "factor", "factor must not be 0 (that is a dead channel)");
      break;
    case ChannelFaultKind::kDead:
      c.from_s = nonnegative(f, w, "from_s", 0.0);
      if (f.contains("value")) c.value = json_number(f["value"], w / "value");
      break;
    case ChannelFaultKind::kDropouts: {
      c.rate_hz = nonnegative(f, w, "rate_hz", 0.0);
      const int64_t len = f.contains("length") ? json_integer(f["length"], w / "length") : 1;
      if (len < 1 || len > 1000000) json_fail(w / "length", "length must be 1..1e6 samples");
      c.length = int(len);
      const std::string mode = f.contains("mode") ? json_string(f["mode"], w / "mode") : "held";
      if (mode != "held" && mode != "lost")
        json_fail(w / "mode", "mode must be \"held\" or \"lost\", got \"" + mode + "\"");
      c.held = mode == "held";
      break;
    }
    case ChannelFaultKind::kClock:
      c.rate_error = json_number_member(f, w, "rate_error");
      if (!(c.rate_error >= 0.0 && c.rate_error <= 0.01)) {
        json_fail(w / "rate_error",
                  "rate_error must be in [0, 0.01] (a fast clock; a slow one is every other "
                  "channel's fast one)");
      }
      c.offset_s = nonnegative(f, w, "offset_s", 0.0);
      if (c.offset_s > 10.0) json_fail(w / "offset_s", "offset_s must be <= 10 s");
      break;
    case ChannelFaultKind::kSwap:
      c.with = json_string_member(f, w, "with");
      break;
    case ChannelFaultKind::kStuck:
      if (!on_input) json_fail(w / "kind", "stuck is an actuator's fault: list it on an input");
      c.from_s = nonnegative(f, w, "from_s", 0.0);
      c.for_s = json_number_member(f, w, "for_s");
      if (!(c.for_s > 0.0)) json_fail(w / "for_s", "for_s must be > 0 s");
      break;
  }
  return c;
}

}  // namespace

const char* to_string(ChannelFaultKind k) {
  for (const KindName& n : kKinds)
    if (n.kind == k) return n.name;
  return "?";
}

std::optional<ChannelFaultKind> channel_fault_kind(const std::string& s) {
  for (const KindName& n : kKinds)
    if (s == n.name) return n.kind;
  return std::nullopt;
}

std::vector<ChannelFault> channel_faults_from_json(const Json& j, const JsonWhere& where,
                                                   bool on_input) {
  if (!j.is_array()) json_fail(where, "faults must be an array of objects");
  std::vector<ChannelFault> out;
  for (size_t i = 0; i < j.size(); ++i) {
    const JsonWhere w = where / i;
    const Json& f = j[i];
    json_require_object(f, w);
    const std::string name = json_string_member(f, w, "kind");
    const auto kind = channel_fault_kind(name);
    if (!kind) {
      json_fail(w / "kind", "unknown fault kind \"" + name +
                                "\" (clock, hum, drift, clip, sign, scale, dead, dropouts, swap, "
                                "stuck)");
    }
    ChannelFault c = channel_fault_fields(f, w, *kind, on_input);
    for (const ChannelFault& o : out) {
      if (o.kind == c.kind && c.kind != ChannelFaultKind::kHum &&
          c.kind != ChannelFaultKind::kStuck)
        json_fail(w / "kind", std::string("a second ") + name + " fault on one channel");
    }
    out.push_back(std::move(c));
  }
  return out;
}

Json channel_faults_to_json(const std::vector<ChannelFault>& faults) {
  Json a = Json::array();
  for (const ChannelFault& c : faults) {
    Json j{{"kind", to_string(c.kind)}};
    switch (c.kind) {
      case ChannelFaultKind::kClip:
        if (c.min) j["min"] = *c.min;
        if (c.max) j["max"] = *c.max;
        break;
      case ChannelFaultKind::kHum:
        j["frequency_hz"] = c.frequency_hz;
        j["amplitude"] = c.amplitude;
        j["harmonics"] = c.harmonics;
        if (c.phase_deg != 0.0) j["phase_deg"] = c.phase_deg;
        break;
      case ChannelFaultKind::kDrift:
        j["rate"] = c.rate;
        if (c.from_s > 0.0) j["from_s"] = c.from_s;
        break;
      case ChannelFaultKind::kSign:
        break;
      case ChannelFaultKind::kScale:
        j["factor"] = c.factor;
        break;
      case ChannelFaultKind::kDead:
        j["from_s"] = c.from_s;
        if (c.value) j["value"] = *c.value;
        break;
      case ChannelFaultKind::kDropouts:
        j["rate_hz"] = c.rate_hz;
        j["length"] = c.length;
        j["mode"] = c.held ? "held" : "lost";
        break;
      case ChannelFaultKind::kClock:
        j["rate_error"] = c.rate_error;
        if (c.offset_s > 0.0) j["offset_s"] = c.offset_s;
        break;
      case ChannelFaultKind::kSwap:
        j["with"] = c.with;
        break;
      case ChannelFaultKind::kStuck:
        j["from_s"] = c.from_s;
        j["for_s"] = c.for_s;
        break;
    }
    a.push_back(std::move(j));
  }
  return a;
}

FaultyChannel::FaultyChannel(std::vector<ChannelFault> faults, double dc, double sample_rate_hz,
                             uint64_t seed, int channel)
    : faults_(std::move(faults)),
      dc_(dc),
      h_(1.0 / sample_rate_hz),
      seed_(seed),
      channel_(channel) {
  // The documented order (the enum's), whatever the file's.
  std::stable_sort(faults_.begin(), faults_.end(),
                   [](const ChannelFault& a, const ChannelFault& b) { return a.kind < b.kind; });
  reset();
}

void FaultyChannel::reset() {
  std::seed_seq seq{static_cast<uint32_t>(seed_), static_cast<uint32_t>(seed_ >> 32),
                    static_cast<uint32_t>(channel_), 0x66617574U};
  rng_.seed(seq);
  past_.clear();
  past_base_ = 0;
  drop_left_ = 0;
  last_ = dc_;
}

double FaultyChannel::apply(int64_t k, double signal, double noise) {
  const double t = double(k) * h_;
  double v = signal + noise;
  for (const ChannelFault& f : faults_) {
    switch (f.kind) {
      case ChannelFaultKind::kClock: {
        // Sample index x <= k the channel's clock actually reads; the history from floor(x) on
        // is kept (it grows by rate_error per sample: 0.05 % of a 300 s run is 150 samples).
        past_.push_back(v);
        const double x = double(k) / (1.0 + f.rate_error) - f.offset_s / h_;
        if (x <= double(past_base_)) {
          v = past_.front();
        } else {
          const int64_t i = int64_t(std::floor(x));
          const double a = x - double(i);
          const size_t at = size_t(i - past_base_);
          v = at + 1 < past_.size() ? (1 - a) * past_[at] + a * past_[at + 1] : past_[at];
          while (past_base_ < i) {
            past_.pop_front();
            ++past_base_;
          }
        }
        break;
      }
      case ChannelFaultKind::kHum:
        for (int m : f.harmonics) {
          v += f.amplitude * std::sin(2 * std::numbers::pi * m * f.frequency_hz * t +
                                      f.phase_deg * std::numbers::pi / 180);
        }
        break;
      case ChannelFaultKind::kDrift:
        if (t >= f.from_s) v += f.rate * (t - f.from_s);
        break;
      case ChannelFaultKind::kClip:
        if (f.min) v = std::max(v, *f.min);
        if (f.max) v = std::min(v, *f.max);
        break;
      case ChannelFaultKind::kSign:
        v = dc_ - (v - dc_);
        break;
      case ChannelFaultKind::kScale:
        v *= f.factor;
        break;
      case ChannelFaultKind::kDead:
        if (t >= f.from_s) v = f.value.value_or(dc_) + noise;
        break;
      case ChannelFaultKind::kDropouts: {
        if (drop_left_ == 0 && f.rate_hz > 0.0 &&
            std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < f.rate_hz * h_) {
          drop_left_ = f.length;
        }
        if (drop_left_ > 0) {
          --drop_left_;
          v = f.held ? last_ : std::numeric_limits<double>::quiet_NaN();
          return v;  // nothing after a dropout: the sample is not there
        }
        break;
      }
      case ChannelFaultKind::kSwap:
      case ChannelFaultKind::kStuck:
        break;  // the simulator's
    }
  }
  last_ = v;
  return v;
}

}  // namespace fralab
