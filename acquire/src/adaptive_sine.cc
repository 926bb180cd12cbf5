#include "fralab/acquire/adaptive_sine.h"

#include <charconv>
#include <cmath>
#include <numbers>

#include "fralab/analyze/repeats.h"
#include "fralab/core/frd.h"
#include "fralab/core/json_util.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"

namespace fralab {

void AdaptiveSineOptions::validate() const {
  if (!(sigma_target >= 0) || !std::isfinite(sigma_target))
    throw InputError("--sigma-target must be > 0 (sigma / |G|, e.g. 0.01), or 0 for none");
  if (pilot_cycles < 2) throw InputError("--pilot-cycles must be >= 2 (sigma needs two blocks)");
}

StepDecision decide_step(int n, const std::vector<double>& rel, int limit,
                         const AdaptiveSineOptions& o) {
  const double t = o.sigma_target;
  StepDecision d;
  for (double s : rel) {
    d.worst_all = std::max(d.worst_all, s);
    if (s * std::sqrt(double(n) / std::max(limit, n)) > kUndetectable)
      ++d.undetectable;  // |G| under 3 sigma even at the limit: nothing there to measure
    else
      d.worst = std::max(d.worst, s);
  }
  if (d.worst > t) {
    const double needed = std::min(double(n) * (d.worst / t) * (d.worst / t), 1e9);  // in all
    const int N1 = o.pilot_cycles;
    const int room = (limit - n) / N1;
    d.more = std::max(0, int(std::min<double>(room, std::ceil((needed - n) / N1)))) * N1;
  }
  if (d.more == 0)
    d.state = rel.empty()                    ? "unusable"
              : d.worst >= 0 && d.worst <= t ? "met"
              : limit - n < o.pilot_cycles   ? "limit"
                                             : "undetectable";
  return d;
}

namespace {

int parse_int(const std::string& s, const std::string& token) {
  int v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || s.empty())
    throw InputError("--adaptive-decided: \"" + token + "\" is not STEP*CYCLES (whole numbers)");
  return v;
}

}  // namespace

std::vector<std::pair<int, int>> parse_decisions(const std::string& text) {
  std::vector<std::pair<int, int>> out;
  for (const std::string& tok : split_list(text, ',')) {
    const auto star = tok.find('*');
    if (star == std::string::npos)
      throw InputError("--adaptive-decided: \"" + tok + "\" is not STEP*CYCLES");
    out.emplace_back(parse_int(tok.substr(0, star), tok), parse_int(tok.substr(star + 1), tok));
  }
  return out;
}

std::string format_decisions(const std::vector<std::pair<int, int>>& d) {
  std::string s;
  for (const auto& [g, c] : d)
    s += (s.empty() ? "" : ",") + std::to_string(g) + "*" + std::to_string(c);
  return s;
}

std::vector<AdaptiveStep> adaptive_steps(const std::vector<Frd>& curves, double target,
                                         const std::vector<int>& limits) {
  AdaptiveSineOptions o;
  o.sigma_target = target;
  std::map<int, std::pair<AdaptiveStep, std::vector<double>>> by_step;
  for (const Frd& f : curves) {
    const PairId id = PairId::parse(f.pair);
    for (const FrdPoint& p : f.points) {
      // The input's own paths X:O and its actuator pair u_X:X.
      if (p.input.empty() || id.input != p.input || (id.command && !id.actuator())) continue;
      auto& [s, rel] = by_step[p.step];
      s.input = p.input;
      s.step = p.step;
      s.f_hz = p.w / (2 * std::numbers::pi);
      s.cycles = std::max(s.cycles, p.n_cycles);
      if (p.valid && p.sigma > 0 && p.mag > 0) rel.push_back(p.sigma / p.mag);
    }
  }
  std::vector<AdaptiveStep> out;
  for (auto& [g, sr] : by_step) {
    auto& [s, rel] = sr;
    if (g < 0 || g >= int(limits.size()))
      throw InputError("adaptive step " + std::to_string(g) + " is outside the run's " +
                       std::to_string(limits.size()) + " steps");
    s.decision = decide_step(s.cycles, rel, limits[size_t(g)], o);
    out.push_back(s);
  }
  return out;
}

Json adaptive_steps_json(const std::vector<AdaptiveStep>& steps) {
  Json v = Json::array();
  std::map<std::string, int> count;
  for (const AdaptiveStep& r : steps) {
    v.push_back({{"input", r.input},
                 {"step", r.step},
                 {"f_hz", r.f_hz},
                 {"cycles", r.cycles},
                 {"worst_rel_sigma", r.decision.worst},
                 {"worst_rel_sigma_all_pairs", r.decision.worst_all},
                 {"undetectable_pairs", r.decision.undetectable},
                 {"state", r.decision.state}});
    ++count[r.decision.state];
  }
  Json j = {{"steps", v}};
  for (const char* k : {"met", "limit", "undetectable", "unusable"}) j[k] = count[k];
  return j;
}

AdaptiveSineCampaign::AdaptiveSineCampaign(std::vector<CampaignInput> inputs,
                                           std::vector<int> excite, const SteppedSineOptions& fixed,
                                           int pilot_cycles, int block, std::string run_id,
                                           const std::vector<std::pair<int, int>>& decided)
    : SegmentCampaign(std::move(inputs), fixed.sample_rate_hz),
      block_(block),
      run_id_(std::move(run_id)) {
  SteppedSineOptions p = fixed;
  p.min_cycles = pilot_cycles;
  p.min_integrate_s = 0;
  const std::vector<SineStep> plan = plan_stepped_sine(p), limits = plan_stepped_sine(fixed);
  if (excite.empty()) throw InputError("campaign: no input to excite");
  if (block < 1) throw InputError("campaign: block must be >= 1");
  for (int i : excite) {
    if (i < 0 || i >= int(inputs_.size())) throw InputError("campaign: input index out of range");
    for (size_t k = 0; k < plan.size(); ++k) {
      steps_.emplace_back(i, plan[k]);
      limit_.push_back(std::max(plan[k].n_cycles, limits[k].n_cycles));
    }
  }
  ext_.resize(steps_.size());
  build(run_id_);
  for (const auto& [g, c] : decided) extend(g, c);
}

int AdaptiveSineCampaign::cycles(int g) const {
  int n = step(g).n_cycles;
  for (int c : ext_.at(size_t(g))) n += c;
  return n;
}

void AdaptiveSineCampaign::extend(int g, int c) {
  if (g < 0 || g >= n_steps())
    throw InputError("adaptive step " + std::to_string(g) + " is outside the campaign's " +
                     std::to_string(n_steps()) + " steps");
  const int N1 = step(g).n_cycles;
  if (c <= 0 || c % N1 != 0 || cycles(g) + int64_t(c) > (1 << 20))
    throw InputError("adaptive step " + std::to_string(g) + ": " + std::to_string(c) +
                     " more cycles is no multiple of its " + std::to_string(N1) +
                     " (or beyond 2^20 in all)");
  ext_[size_t(g)].push_back(c);
  decided_.emplace_back(g, c);
  build(run_id_);
}

void AdaptiveSineCampaign::build(const std::string& run_id) {
  segs_.clear();
  events_.clear();
  total_ = 0;
  start_.assign(steps_.size(), 0);
  end_.assign(steps_.size(), 0);
  double phi = 0.0;
  int64_t seq = 0;
  const int n_steps = int(steps_.size());
  for (int g = 0; g < n_steps; ++g) {
    const auto& [i, s] = steps_[size_t(g)];
    StatusEvent e = sine_step_settle(run_id, i, g, n_steps, s, phi);
    e.seq = seq++;
    start_[size_t(g)] = total_;
    events_.push_back(e);
    if (s.settle_samples > 0) phi = add_segment(i, s.settle_samples, s.f_hz, 0.0, phi);
    std::vector<int> windows = {s.n_cycles};
    windows.insert(windows.end(), ext_[size_t(g)].begin(), ext_[size_t(g)].end());
    for (int c : windows) {
      e.seq = seq++;
      e.state = RunState::kIntegrate;
      e.sample = total_;
      e.ref_phase_rad = phi;
      e.n_cycles = c;
      e.n_samples = s.integrate_samples * (c / s.n_cycles);  // c: whole pilots, the same f
      events_.push_back(e);
      phi = add_segment(i, e.n_samples, s.f_hz, 0.0, phi);
    }
    end_[size_t(g)] = total_;
    // The sine goes on to the next block boundary, where the next step's settle starts.
    if (const int64_t fill = (block_ - total_ % block_) % block_; fill > 0)
      phi = add_segment(i, fill, s.f_hz, 0.0, phi);
  }
  // One block at the operating point ends the run: the last step's decision comes before it.
  total_ += block_;
  finish(run_id, seq, n_steps, Excitation::kStepped);
}

AutoIntegrator::AutoIntegrator(AdaptiveSineCampaign& c, std::vector<std::string> outputs,
                               AdaptiveSineOptions o, int64_t first_sample)
    : c_(c), outputs_(std::move(outputs)), o_(o) {
  o_.validate();
  while (g_ < c_.n_steps() && c_.step_start(g_) < first_sample) ++g_;
  feed_events();
}

AutoIntegrator::~AutoIntegrator() = default;

int64_t AutoIntegrator::decision_sample() const {
  return g_ < c_.n_steps() ? c_.window_end(g_) : -1;
}

std::pair<int64_t, int64_t> AutoIntegrator::needed_samples() const {
  if (g_ >= c_.n_steps()) return {0, 0};
  return {c_.step_start(g_), c_.window_end(g_)};
}

void AutoIntegrator::feed_events() {
  if (g_ >= c_.n_steps()) return;
  const int x = c_.input_of(g_);
  if (an_.empty()) {  // the step's analysers, fresh for each step (they hold its samples only)
    const std::string in = c_.inputs()[size_t(x)].name;
    AnalyzerOptions ao;
    ao.input = in;
    const auto store = std::make_shared<SampleStore>();  // each block's channels kept once
    for (const std::string& out : outputs_)
      an_.push_back(std::make_unique<PairAnalyzer>(in + ":" + out, ao, store));
    an_.push_back(std::make_unique<PairAnalyzer>(PairId::actuator_pair(in).str(), ao, store));
  }
  const auto& ev = c_.events();
  while (fed_ < ev.size() && ev[fed_].sample < c_.window_end(g_) &&
         ev[fed_].state != RunState::kDone) {
    if (ev[fed_].step == g_)
      for (auto& a : an_) a->on_status(ev[fed_]);
    ++fed_;
  }
}

void AutoIntegrator::on_block(const Block& b) {
  if (g_ >= c_.n_steps()) return;
  if (b.start_sample + b.n_samples <= c_.step_start(g_) || b.start_sample >= c_.window_end(g_))
    return;
  for (auto& a : an_) {
    a->on_block(b);
    for (const FrdPoint& p : a->take_new_points()) {
      Frd one;
      one.pair = a->pair();
      one.points = {p};
      auto& [merged, windows] = merged_[a->pair()];
      merged = windows == 0 ? one : merge_repeated(merged, one);
      ++windows;
    }
  }
}

bool AutoIntegrator::decide() {
  if (g_ >= c_.n_steps()) return true;
  // Every pair's point of the window ending at E: the merged points hold all the step's cycles.
  const int n = c_.cycles(g_);
  const size_t windows = 1 + c_.extensions(g_).size();
  std::vector<double> rel;
  for (const auto& a : an_) {
    auto it = merged_.find(a->pair());
    if (it == merged_.end() || it->second.second < windows) return false;  // not in yet
    for (const FrdPoint& p : it->second.first.points)
      if (p.valid && p.sigma > 0 && p.mag > 0) rel.push_back(p.sigma / p.mag);
  }
  AdaptiveStep r;
  r.decision = decide_step(n, rel, c_.limit(g_), o_);
  if (r.decision.more > 0) {
    c_.extend(g_, r.decision.more);
    feed_events();
    return true;
  }
  r.input = c_.inputs()[size_t(c_.input_of(g_))].name;
  r.step = g_;
  r.f_hz = c_.step(g_).f_hz;
  r.cycles = n;
  results_.push_back(r);
  an_.clear();
  merged_.clear();
  ++g_;
  feed_events();
  return true;
}

}  // namespace fralab
