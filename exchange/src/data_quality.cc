// The data-quality checks driven over a run's channels, the mending of a series, and the JSON
// (data_quality.h; the checks and the mending in data_quality_*.cc, data_quality_checks.h).
#include "fralab/exchange/data_quality.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "data_quality_checks.h"
#include "fralab/core/numerics.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"

namespace fralab {
namespace {

constexpr std::pair<DataFaultKind, const char*> kKindWords[] = {
    {DataFaultKind::kLost, "lost_samples"},     {DataFaultKind::kHeld, "held_samples"},
    {DataFaultKind::kClipping, "clipping"},     {DataFaultKind::kHum, "hum"},
    {DataFaultKind::kDrift, "drift"},           {DataFaultKind::kClock, "clock"},
    {DataFaultKind::kNoResponse, "no_response"}};

bool checked_channel(const std::string& c) {
  return !commanded_input(c) && !c.starts_with("ref_") && c != "underrun";
}

}  // namespace

const char* to_string(DataFaultKind k) { return enum_word(kKindWords, k); }

std::map<std::string, ClockEstimate> pool_clocks(const std::vector<ClockEstimate>& all) {
  std::map<std::string, std::pair<double, double>> sums;  // channel -> (sum w, sum w eps)
  std::map<std::string, ClockEstimate> out;
  for (const ClockEstimate& e : all) {
    if (!(e.sigma > 0)) continue;
    auto& [w, wx] = sums[e.channel];
    w += 1 / (e.sigma * e.sigma);
    wx += e.eps / (e.sigma * e.sigma);
    if (!out.count(e.channel)) out[e.channel] = e;  // its time and run: the first's
  }
  for (auto& [ch, e] : out) {
    e.eps = sums[ch].second / sums[ch].first;
    e.sigma = 1 / std::sqrt(sums[ch].first);
  }
  return out;
}

void DataQualityOptions::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(std::string("data quality: ") + name + " must be a positive number");
  };
  positive(max_gap_s, "max_gap_s");
  positive(mains_search_hz, "mains_search_hz");
  positive(hum_ratio, "hum_ratio");
  positive(drift_sigmas, "drift_sigmas");
  positive(clock_sigmas, "clock_sigmas");
  positive(min_clock, "min_clock");
  if (max_harmonic < 1 || max_harmonic > 20)
    throw InputError("data quality: max_harmonic must be in 1..20");
}

bool DataQuality::changes_curves() const {
  return any_mended() || std::any_of(faults.begin(), faults.end(), [](const DataFault& f) {
           return f.kind == DataFaultKind::kClipping;
         });
}

bool DataQuality::any_mended() const {
  return std::any_of(faults.begin(), faults.end(), [](const DataFault& f) { return f.mended; });
}

DataQuality check_data_quality(const TimeSeries& s, const Schedule& schedule,
                               const DataQualityOptions& o) {
  o.validate();
  DataQuality q;
  const std::vector<dq::Window> windows = dq::windows_of(schedule, s);
  TimeSeries work = s;
  for (size_t c = 0; c < s.channels.size(); ++c) {
    const std::string& ch = s.channels[c];
    if (!checked_channel(ch)) continue;
    q.checked.push_back(ch);
    const double* raw = s.samples.data() + c * size_t(s.n_samples);
    double* x = work.samples.data() + c * size_t(s.n_samples);
    std::vector<DataFault> found;
    dq::check_lost(ch, raw, s, o, &found);
    // Repeats and flat tops are faults only where noise makes them improbable.
    if (!o.noise_free && dq::noisy(raw, s.n_samples)) {
      const auto [hi, lo] = dq::check_clipping(ch, raw, s, &found);
      dq::check_held(ch, raw, s, hi, lo, o, &found);
    }
    // The spectral checks see the gaps mended (a NaN would spoil every period it falls in).
    std::vector<const DataFault*> so_far;
    for (const DataFault& f : found) so_far.push_back(&f);
    dq::mend_channel(x, s, so_far);
    const size_t before_hum = found.size();
    dq::check_hum(ch, x, s, windows, o, &found);
    std::vector<const DataFault*> hums;
    for (size_t i = before_hum; i < found.size(); ++i) hums.push_back(&found[i]);
    dq::mend_channel(x, s, hums);
    // The periods compared with clipping and gaps filled: a clipped peak moves a period's mean
    // and phase, a gap's straight line its higher lines.
    std::vector<const DataFault*> holes;
    for (const DataFault& f : found) holes.push_back(&f);
    if (const std::vector<bool> c = dq::missing_samples(raw, s, holes); !c.empty())
      dq::fill_missing(x, s, windows, c);
    // Each window's blocks, transformed once for the tests that compare periods.
    std::vector<dq::BlockValues> values;
    for (const dq::Window& w : windows)
      values.push_back(dq::block_values(w, x, s.start_sample, s.sample_rate_hz));
    // The spans without response first: the periods they set aside enter neither the drift nor
    // the clock (a dead stretch's phases are noise).
    std::vector<DataFault> silent;
    dq::check_no_response(ch, s, windows, values, &silent);
    dq::check_silent_eighths(ch, x, s, windows, &silent);
    dq::leave_out_spans(windows, silent, values);
    // A channel silent from some time on may have carried a hum only while it lived: looked for
    // again over the stretch before its first silent span.
    if (hums.empty() && !silent.empty()) {
      int64_t live = s.n_samples;
      for (const DataFault& f : silent)
        for (const auto& span : f.spans) live = std::min(live, span.first - s.start_sample);
      std::vector<DataFault> late;
      if (live > 0) dq::check_hum(ch, x, s, windows, o, &late, live);
      std::vector<const DataFault*> late_hums;
      for (const DataFault& f : late) late_hums.push_back(&f);
      dq::mend_channel(x, s, late_hums);
      found.insert(found.begin() + long(before_hum), std::make_move_iterator(late.begin()),
                   std::make_move_iterator(late.end()));
    }
    dq::check_drift_and_clock(ch, x, s, windows, values, o, &found, &q.clocks);
    for (DataFault& f : silent) found.push_back(std::move(f));
    for (DataFault& f : found) q.faults.push_back(std::move(f));
  }
  return q;
}

TimeSeries mend_series(const TimeSeries& s, const DataQuality& q, const Schedule& schedule) {
  const std::vector<dq::Window> windows = dq::windows_of(schedule, s);
  TimeSeries out = s;
  for (size_t c = 0; c < s.channels.size(); ++c) {
    std::vector<const DataFault*> mine;
    for (const DataFault& f : q.faults)
      if (f.channel == s.channels[c] && f.mended) mine.push_back(&f);
    if (!mine.empty())
      dq::mend_channel(out.samples.data() + c * size_t(s.n_samples), s, mine, &windows);
  }
  return out;
}

void widen_for_mending(std::vector<Frd>& curves, const DataQuality& q) {
  for (Frd& c : curves) {
    const PairId id = PairId::parse(c.pair);
    for (const DataFault& f : q.faults) {
      if (f.channel != id.e1() && f.channel != id.output) continue;
      for (FrdPoint& p : c.points) {
        if (!p.valid || !(p.sigma > 0)) continue;
        double extra = 0;
        if (f.kind == DataFaultKind::kClock && f.mended) extra = p.mag * p.w * f.sigma * f.to_s;
        if (f.kind == DataFaultKind::kClipping && !f.mended) extra = p.mag * f.size;
        p.sigma = std::sqrt(p.sigma * p.sigma + extra * extra);
      }
    }
  }
}

Json data_quality_to_json(const DataQuality& q) {
  Json faults = Json::array();
  for (const DataFault& f : q.faults) {
    faults.push_back({{"channel", f.channel},
                      {"kind", to_string(f.kind)},
                      {"from_s", f.from_s},
                      {"to_s", f.to_s},
                      {"size", f.size},
                      {"sigma", f.sigma},
                      {"frequency_hz", f.frequency_hz},
                      {"phase_deg", f.phase_deg},
                      {"level", f.level},
                      {"mended", f.mended},
                      {"action", f.action},
                      {"text", f.text}});
  }
  return Json{{"checked", q.checked}, {"faults", faults}};
}

DataQuality data_quality_from_json(const Json& j, const JsonWhere& where) {
  json_require_object(j, where);
  DataQuality q;
  const Json& checked = json_array_member(j, where, "checked");
  for (size_t i = 0; i < checked.size(); ++i)
    q.checked.push_back(json_string(checked[i], where / "checked" / i));
  const Json& faults = json_array_member(j, where, "faults");
  for (size_t i = 0; i < faults.size(); ++i) {
    const JsonWhere w = where / "faults" / i;
    const Json& f = faults[i];
    json_require_object(f, w);
    DataFault d;
    d.channel = json_string_member(f, w, "channel");
    const std::string kind = json_string_member(f, w, "kind");
    const auto k = enum_from_word(kKindWords, kind);
    if (!k) json_fail(w / "kind", "unknown data fault kind \"" + kind + "\"");
    d.kind = *k;
    d.from_s = json_number_member(f, w, "from_s");
    d.to_s = json_number_member(f, w, "to_s");
    d.size = json_number_member(f, w, "size");
    d.sigma = json_number_member(f, w, "sigma", 0.0);
    d.frequency_hz = json_number_member(f, w, "frequency_hz", 0.0);
    d.phase_deg = json_number_member(f, w, "phase_deg", 0.0);
    d.level = json_number_member(f, w, "level", 0.0);
    d.mended = f.contains("mended") && json_bool(f["mended"], w / "mended");
    d.action = f.contains("action") ? json_string(f["action"], w / "action") : "";
    d.text = f.contains("text") ? json_string(f["text"], w / "text") : "";
    q.faults.push_back(std::move(d));
  }
  return q;
}

}  // namespace fralab
