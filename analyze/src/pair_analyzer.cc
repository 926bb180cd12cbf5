#include "fralab/analyze/pair_analyzer.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>

#include "fralab/analyze/bla.h"
#include "fralab/analyze/fourier_filter.h"
#include "fralab/analyze/period_fft.h"
#include "fralab/analyze/repeats.h"
#include "fralab/core/pair_id.h"
#include "line_statistics.h"
#include "orthogonal_multisine.h"

namespace fralab {

using namespace analyze_detail;

void AnalyzerOptions::validate() const {
  if (max_blocks < 2)
    throw InputError("analyzer: max_blocks must be >= 2 (sigma needs two blocks)");
  if (reorder_slack_samples < 0) throw InputError("analyzer: reorder_slack_samples must be >= 0");
}

PairAnalyzer::PairAnalyzer(const std::string& pair, const AnalyzerOptions& options,
                           std::shared_ptr<SampleStore> store)
    : pair_(pair),
      opt_(options),
      store_(store ? std::move(store) : std::make_shared<SampleStore>()) {
  opt_.validate();
  const PairId id = PairId::parse(pair);
  e1_ = id.e1();
  e2_ = id.output;
  orthogonal_ = std::make_unique<OrthogonalRealisations>(e1_, e2_, opt_.distortion_threshold);
  for (const std::string& ch : {e1_, e2_, std::string("ref_phase")}) store_->keep(ch);
  reader_ = store_->add_reader();
}

PairAnalyzer::~PairAnalyzer() { store_->remove_reader(reader_); }

const double* PairAnalyzer::samples(const std::string& ch, int64_t n) const {
  return store_->channel(ch)->data() + (n - store_->base());
}

std::function<const double*(const std::string&)> PairAnalyzer::window_channel(
    const StatusEvent& st) const {
  return [this, st](const std::string& ch) -> const double* {
    const std::vector<double>* v = store_->channel(ch);
    if (!v || st.sample - store_->base() + st.n_samples > int64_t(v->size())) return nullptr;
    const double* c = samples(ch, st.sample);
    for (int64_t k = 0; k < st.n_samples; ++k)
      if (std::isnan(c[k])) return nullptr;
    return c;
  };
}

bool PairAnalyzer::wants(const StatusEvent& st) const {
  // st.inputs lists every plant input; amplitudes > 0 mark the excited ones.
  auto excited = [&](const std::string& in) {
    for (size_t i = 0; i < st.inputs.size(); ++i) {
      if (st.inputs[i] == in) return i < st.amplitudes.size() && st.amplitudes[i] > 0.0;
    }
    return false;
  };
  auto is_input = [&](const std::string& in) {
    return std::find(st.inputs.begin(), st.inputs.end(), in) != st.inputs.end();
  };
  if (!opt_.input.empty()) return excited(opt_.input);
  for (const std::string& ch : {e1_, e2_}) {
    const std::string base = commanded_input(ch).value_or(ch);
    if (is_input(base) && !excited(base)) return false;
  }
  return true;
}

// The inputs (indices into st.inputs, ascending) of an orthogonal multisine: those listed for a
// line that more than one input excites; empty for any other status.
static std::vector<int> orthogonal_inputs(const StatusEvent& st) {
  std::map<int, std::set<int>> by_line;
  bool shared = false;
  for (size_t j = 0; j < st.lines.size() && j < st.line_input.size(); ++j) {
    auto& s = by_line[st.lines[j]];
    s.insert(st.line_input[j]);
    shared = shared || s.size() > 1;
  }
  if (!shared) return {};
  std::set<int> all;
  for (int i : st.line_input) all.insert(i);
  return {all.begin(), all.end()};
}

void PairAnalyzer::on_status(const StatusEvent& st) {
  if (st.state == RunState::kSettle) {
    settle_step_ = st.step;
    settle_from_ = st.sample;
  }
  if (st.state == RunState::kIntegrate) {
    if (!wants(st)) return;
    // A window of more than 10^9 samples (11 days at 1 kHz), before the run or from beyond 2^62
    // samples (where its end plus the reorder slack would overflow), or a multisine line of an
    // input the status does not list, is no status the acquisition makes: a corrupt record.
    bool lines_ok = st.lines.size() == st.line_input.size();
    for (int i : st.line_input) lines_ok = lines_ok && i >= 0 && i < int(st.inputs.size());
    if (st.n_samples <= 0 || st.n_cycles <= 0 || !(st.frequency_hz > 0) ||
        !(st.sample_rate_hz > 0) || st.n_samples > 1000000000 || st.sample < 0 ||
        st.sample > (int64_t(1) << 62) || !std::isfinite(st.frequency_hz) ||
        !std::isfinite(st.sample_rate_hz) ||
        (st.excitation == Excitation::kMultisine && !lines_ok)) {
      FrdPoint p;
      p.step = st.step;
      p.valid = false;
      p.note = lines_ok ? "integrate status with no window (n_samples " +
                              std::to_string(st.n_samples) + ")"
                        : "multisine status with a line of no listed input (line_input)";
      fresh_.push_back(p);
      points_.push_back(p);
      return;
    }
    Window w{st, settle_step_ == st.step && settle_from_ <= st.sample ? settle_from_ : st.sample,
             st.excitation == Excitation::kMultisine ? orthogonal_inputs(st) : std::vector<int>{}};
    for (int i : w.ins)
      for (const std::string& ch : {command_channel(st.inputs[i]), st.inputs[i]}) store_->keep(ch);
    pending_[st.sample] = std::move(w);
  } else if (st.state == RunState::kDone || st.state == RunState::kAbort) {
    done_seen_ = true;
    done_sample_ = st.sample;
  }
  try_complete(false);
}

void PairAnalyzer::on_block(const Block& b) {
  const int c1 = b.channel_index(e1_), c2 = b.channel_index(e2_);
  if (c1 < 0 || c2 < 0) {
    throw InputError("tape block seq " + std::to_string(b.seq) + " has no channel " +
                     (c1 < 0 ? e1_ : e2_) + " (pair " + pair_ + ")");
  }
  if (seqs_.count(b.seq)) return;  // duplicate delivery: the first copy counts
  // Samples are kept contiguously from the store's base: a block 10^7 samples (2.8 h at 1 kHz)
  // beyond what is kept (a gap no retransmitting run leaves, and 250 MB to hold), or 10^8 before
  // it, is no block of this run's stream (a corrupt record).
  const int64_t base = store_->base(), kept_end = store_->end();
  if (b.start_sample > kept_end + 10000000 || b.start_sample + b.n_samples < base - 100000000)
    throw InputError("tape block seq " + std::to_string(b.seq) + " starts at sample " +
                     std::to_string(b.start_sample) + ", far from the samples so far (" +
                     std::to_string(base) + "-" + std::to_string(kept_end) + "): corrupt");
  ++blocks_seen_;
  seqs_[b.seq] = {b.start_sample, b.start_sample + b.n_samples};
  const int64_t end = b.start_sample + b.n_samples;
  // Stored once for every pair sharing the store (the first of them to see the block). The first
  // block: kept from the run's start, or from reorder slack before it when it is late (an
  // analyser started mid-run does not hold the hours before it joined).
  store_->add(b, opt_.reorder_slack_samples);
  held_.add(b);  // a free-running plant's dry buffer
  max_seen_ = std::max(max_seen_, end);
  try_complete(false);
}

bool PairAnalyzer::covers(int64_t a, int64_t b) const {
  if (a < store_->base() || b > store_->end()) return false;
  for (int64_t n = a; n < b; ++n) {
    if (!store_->have(n)) return false;
  }
  return true;
}

std::string PairAnalyzer::describe_gaps(int64_t a, int64_t b) const {
  std::string out;
  auto add = [&](int64_t first, int64_t last) {
    out += (out.empty() ? "" : ", ") + std::string("samples ") + std::to_string(first) + "-" +
           std::to_string(last);
  };
  auto have = [&](int64_t n) { return store_->have(n); };
  // Samples outside what is stored are one gap each side (no sample-by-sample walk there).
  const int64_t lo = std::max(a, store_->base()), hi = std::min(b, store_->end());
  if (lo >= hi) {
    add(a, b - 1);
  } else {
    if (a < lo) add(a, lo - 1);
    for (int64_t n = lo; n < hi;) {
      if (have(n)) {
        ++n;
        continue;
      }
      const int64_t first = n;
      while (n < hi && !have(n)) ++n;
      add(first, n - 1);
    }
    if (hi < b) add(hi, b - 1);
  }
  // Name the sequence numbers that are absent between the lowest and highest seen.
  if (!seqs_.empty()) {
    // As ranges ("7", "9-12"), at most 10 of them.
    std::string missing;
    int ranges = 0;
    int64_t prev = seqs_.begin()->first;
    for (auto it = std::next(seqs_.begin()); it != seqs_.end() && ranges <= 10; ++it) {
      if (it->first > prev + 1) {
        missing += (missing.empty() ? "" : ",") +
                   (++ranges > 10 ? std::string("...")
                    : it->first == prev + 2
                        ? std::to_string(prev + 1)
                        : std::to_string(prev + 1) + "-" + std::to_string(it->first - 1));
      }
      prev = it->first;
    }
    if (!missing.empty()) out += " (tape block seq " + missing + " missing)";
    std::string bad;
    for (int64_t q : corrupt_)
      if (!seqs_.count(q)) bad += (bad.empty() ? "" : ",") + std::to_string(q);
    if (!bad.empty()) out += " (tape block seq " + bad + " failed its checksum)";
  }
  return out;
}

void PairAnalyzer::try_complete(bool force) {
  for (auto it = pending_.begin(); it != pending_.end();) {
    const StatusEvent& st = it->second.st;
    const int64_t a = st.sample, b = st.sample + st.n_samples;
    bool ready = covers(a, b);
    bool expired = force || (max_seen_ >= b + opt_.reorder_slack_samples) ||
                   (done_seen_ && max_seen_ >= done_sample_ && !ready);
    if (!ready && !expired) {
      ++it;
      continue;
    }
    FrdPoint p;
    if (ready) {  // samples the plant held (its command buffer ran dry) are not the excitation
      if (const auto held = held_.within(it->second.from, b)) {
        p.w = 2 * std::numbers::pi * st.frequency_hz;
        p.step = st.step;
        p.n_cycles = st.n_cycles;
        p.valid = false;
        p.note = "the plant's command buffer ran dry in the step (samples " +
                 std::to_string(held->first) + "-" + std::to_string(held->second) +
                 " held): not the excitation; the step is repeated";
        p.input = first_excited(st).first;
        points_.push_back(p);
        fresh_.push_back(p);
        it = pending_.erase(it);
        continue;
      }
    }
    if (!it->second.ins.empty()) {
      OrthogonalExperiment ex;
      if (ready) {
        ex = orthogonal_experiment(st, it->second.ins, samples(e1_, st.sample),
                                   samples(e2_, st.sample), window_channel(st));
      } else {
        ex.valid = false;
        ex.note = "incomplete window: " + describe_gaps(a, b);
      }
      for (const FrdPoint& q : orthogonal_->add(st, it->second.ins, std::move(ex))) {
        realisation_points_.push_back(q);
        fresh_.push_back(q);
      }
      it = pending_.erase(it);
      continue;
    }
    if (ready && st.excitation == Excitation::kMultisine) {
      for (const FrdPoint& q : compute_multisine(it->second)) {
        realisation_points_.push_back(q);
        fresh_.push_back(q);
      }
      it = pending_.erase(it);
      continue;
    }
    if (ready) {
      p = compute(it->second);
    } else {
      p.w = 2 * std::numbers::pi * st.frequency_hz;
      p.step = st.step;
      p.n_cycles = st.n_cycles;
      p.valid = false;
      p.note = "incomplete window: " + describe_gaps(a, b);
      p.input = first_excited(st).first;
    }
    points_.push_back(p);
    fresh_.push_back(p);
    it = pending_.erase(it);
  }
  trim();
}

void PairAnalyzer::flush() {
  try_complete(true);
  // Orthogonal multisine realisations whose experiments never all arrived (their status lost).
  for (const FrdPoint& p : orthogonal_->incomplete()) {
    points_.push_back(p);
    fresh_.push_back(p);
  }
}

void PairAnalyzer::trim() {
  // This pair needs samples from its earliest pending window (or the newest data if none is
  // pending); the store drops what no pair needs.
  int64_t keep =
      pending_.empty() ? max_seen_ - opt_.reorder_slack_samples : pending_.begin()->first;
  store_->release(reader_, std::min(keep, max_seen_));
}

FrdPoint PairAnalyzer::compute(const Window& win) {
  const StatusEvent& st = win.st;
  const size_t L = size_t(st.n_samples);
  const double* a = samples(e1_, st.sample);
  const double* b = samples(e2_, st.sample);
  const double dphi = 2 * std::numbers::pi * st.frequency_hz / st.sample_rate_hz;
  // A stepped sine's reference is the status's phase and frequency; a sweep's is the recorded
  // per-sample reference phase (tape channel ref_phase).
  const bool sweep = st.excitation == Excitation::kSweep;
  const double* rp = samples("ref_phase", st.sample);
  if (sweep) {
    for (size_t k = 0; k < L; ++k) {
      if (std::isnan(rp[k])) {
        FrdPoint bad;
        bad.w = 2 * std::numbers::pi * st.frequency_hz;
        bad.step = st.step;
        bad.valid = false;
        bad.note = "sweep window without the ref_phase channel on the tape";
        return bad;
      }
    }
  }
  auto reference = [&](int h) {
    return sweep ? make_reference(rp, L, h) : make_reference(L, st.ref_phase_rad, dphi, h);
  };
  Reference ref = reference(1);
  // Window means (exactly DC + noise mean: the window holds whole cycles), removed for the blocks.
  double m1 = 0, m2 = 0;
  for (size_t k = 0; k < L; ++k) {
    m1 += a[k];
    m2 += b[k];
  }
  m1 /= double(L);
  m2 /= double(L);
  std::vector<double> d1(L), d2(L);
  for (size_t k = 0; k < L; ++k) {
    d1[k] = a[k] - m1;
    d2[k] = b[k] - m2;
  }
  const Complex p1 = fourier_phasor(d1.data(), ref, 0, L),
                p2 = fourier_phasor(d2.data(), ref, 0, L);
  FrdPoint p;
  p.w = 2 * std::numbers::pi * st.frequency_hz;
  p.step = st.step;
  p.n_cycles = st.n_cycles;
  std::tie(p.input, p.amplitude) = first_excited(st);
  if (std::abs(p1) == 0.0 || !std::isfinite(std::abs(p1)) || !std::isfinite(std::abs(p2))) {
    p.valid = false;
    p.note = std::abs(p1) == 0.0 ? "channel " + e1_ + " has no component at the test frequency"
                                 : "non-finite samples in the window";
    return p;
  }
  const Complex r = p2 / p1;
  p.mag = std::abs(r);
  p.phase_deg = std::arg(r) * 180.0 / std::numbers::pi;
  const int K = std::max(2, std::min(opt_.max_blocks, st.n_cycles));
  // Each block's phasors by least squares: a block that splits a cycle would leak the
  // negative-frequency image into the filter's sums by an amount that turns with its starting
  // phase, differently in the two channels, and their ratios would spread with no noise at all.
  std::vector<Complex> b1(K), b2(K);
  for (int k = 0; k < K; ++k) {
    size_t s = L * k / K, e = L * (k + 1) / K;
    std::tie(b1[k], b2[k]) = fitted_phasors(d1.data(), d2.data(), ref, s, e);
  }
  double se = 0, s11 = 0, s22 = 0;
  Complex s12 = 0;
  for (int k = 0; k < K; ++k) {
    se += std::norm(b2[k] - r * b1[k]);
    s11 += std::norm(b1[k]);
    s22 += std::norm(b2[k]);
    s12 += std::conj(b1[k]) * b2[k];
  }
  p.sigma = positive_sigma(std::sqrt(se / (double(K) * (K - 1))) / std::abs(p1), p.mag);
  p.coherence = (s11 > 0 && s22 > 0) ? std::norm(s12) / (s11 * s22) : 0.0;
  for (int h : {2, 3}) {
    Reference rh = reference(h);
    double rel = std::abs(fourier_phasor(d2.data(), rh, 0, L)) / std::max(std::abs(p2), 1e-300);
    (h == 2 ? p.h2_rel : p.h3_rel) = rel;
  }
  return p;
}

// One line k of a one-window multisine of period P samples from the M periods' spectra X1, X2 of
// the pair's channels
// (m1, m2 their means at k): R = m2 / m1 into q with its sigma (the spread of X2 - R X1 pooled
// over the line and its nearest unexcited neighbours), coherence, nl_rel and, for a pair from the
// input's command (e1 = u_X), the line's command amplitude; invalid where E1 has nothing at k.
static void multisine_line(const std::vector<std::vector<std::complex<double>>>& X1,
                           const std::vector<std::vector<std::complex<double>>>& X2,
                           std::complex<double> m1, std::complex<double> m2, int k, int P,
                           const std::vector<bool>& excited, const std::string& e1, FrdPoint& q) {
  const int M = int(X1.size());
  if (std::abs(m1) == 0.0 || !std::isfinite(std::abs(m1)) || !std::isfinite(std::abs(m2))) {
    q.valid = false;
    q.note = "channel " + e1 + " has no component at line " + std::to_string(k);
    return;
  }
  const std::complex<double> r = m2 / m1;
  q.mag = std::abs(r);
  q.phase_deg = std::arg(r) * 180 / std::numbers::pi;
  double se = 0, s11 = 0, s22 = 0;
  std::complex<double> s12 = 0;
  for (int p = 0; p < M; ++p) {
    se += std::norm(X2[p][k] - r * X1[p][k]);
    s11 += std::norm(X1[p][k]);
    s22 += std::norm(X2[p][k]);
    s12 += std::conj(X1[p][k]) * X2[p][k];
  }
  // Non-excited neighbours: the nearest unexcited line on each side.
  const std::vector<int> nb = unexcited_neighbours(excited, k, P);
  // The spread over periods of z = X2 - r X1, pooled over the line (where z's mean is 0) and
  // its neighbours (about their own mean: a periodic distortion there cancels), as the
  // orthogonal design's: a few periods' spread on one line alone is too few degrees of freedom.
  for (int kk : nb) se += period_spread(M, [&](int p) { return X2[p][kk] - r * X1[p][kk]; });
  se /= double(1 + nb.size());
  q.sigma = positive_sigma(std::sqrt(se / (double(M) * (M - 1))) / std::abs(m1), q.mag);
  if (e1 == command_channel(q.input)) q.line_amplitude = 2 * std::abs(m1) / P;
  q.coherence = std::norm(s12) / (s11 * s22);
  double lvl = 0;
  for (int kk : nb) {
    std::complex<double> v = 0;
    for (int p = 0; p < M; ++p) v += X2[p][kk];
    lvl += std::abs(v / double(M));
  }
  q.nl_rel = nb.empty() ? 0.0 : lvl / double(nb.size()) / std::max(std::abs(m2), 1e-300);
}

std::vector<FrdPoint> PairAnalyzer::compute_multisine(const Window& win) {
  const StatusEvent& st = win.st;
  const int P = st.period_samples;
  const int M = P > 0 ? int(st.n_samples / P) : 0;
  std::vector<FrdPoint> out;
  auto invalid = [&](const std::string& why) {
    FrdPoint p;
    p.step = st.step;
    p.valid = false;
    p.note = why;
    return std::vector<FrdPoint>{p};
  };
  if (P < 4 || M < 2 || st.lines.size() != st.line_input.size())
    return invalid("multisine status without periods or lines");
  // The pair's input: the one named by E1 or E2 (u_X or X); none: every line.
  int want = -1;
  for (size_t i = 0; i < st.inputs.size(); ++i) {
    for (const std::string& ch : {e1_, e2_}) {
      if (ch == st.inputs[i] || ch == command_channel(st.inputs[i])) want = int(i);
    }
  }
  // Spectra of every period of both channels (window mean removed: DC does not touch lines k >= 1).
  PeriodFft fft(P);
  std::vector<std::vector<std::complex<double>>> X1(M), X2(M);
  const double* a = samples(e1_, st.sample);
  const double* b = samples(e2_, st.sample);
  for (int p = 0; p < M; ++p) {
    X1[p] = fft(a + size_t(p) * P);
    X2[p] = fft(b + size_t(p) * P);
  }
  std::vector<bool> excited(P / 2 + 1, false);
  for (int k : st.lines)
    if (k >= 0 && k <= P / 2) excited[k] = true;
  const double df = st.sample_rate_hz / P;
  for (size_t j = 0; j < st.lines.size(); ++j) {
    const int k = st.lines[j];
    if (k < 1 || k >= P / 2 || (want >= 0 && st.line_input[j] != want)) continue;
    std::complex<double> m1 = 0, m2 = 0;
    for (int p = 0; p < M; ++p) {
      m1 += X1[p][k];
      m2 += X2[p][k];
    }
    m1 /= double(M);
    m2 /= double(M);
    FrdPoint q;
    q.w = 2 * std::numbers::pi * k * df;
    q.step = st.step;
    q.n_cycles = M;
    q.input = st.inputs[st.line_input[j]];
    q.amplitude =
        st.amplitudes.size() > size_t(st.line_input[j]) ? st.amplitudes[st.line_input[j]] : 0.0;
    multisine_line(X1, X2, m1, m2, k, P, excited, e1_, q);
    out.push_back(q);
  }
  return out;
}

std::vector<FrdPoint> PairAnalyzer::take_new_points() {
  std::vector<FrdPoint> out;
  out.swap(fresh_);
  return out;
}

Frd PairAnalyzer::frd() const {
  Frd f;
  f.pair = pair_;
  // An adaptive stepped sine's windows of one step are one point (analyze/repeats.h).
  f = merge_repeated(f, Frd{pair_, points_, ""});
  for (const FrdPoint& p : best_linear_approximation(realisation_points_)) f.points.push_back(p);
  std::stable_sort(f.points.begin(), f.points.end(),
                   [](const FrdPoint& x, const FrdPoint& y) { return x.w < y.w; });
  return f;
}

std::vector<Frd> analyse_run_in_memory(const std::vector<StatusEvent>& events,
                                       const std::vector<Block>& blocks,
                                       const std::vector<std::string>& pairs,
                                       const AnalyzerOptions& options) {
  const auto store = std::make_shared<SampleStore>();
  std::vector<std::unique_ptr<PairAnalyzer>> an;
  for (const std::string& p : pairs)
    an.push_back(std::make_unique<PairAnalyzer>(p, options, store));
  for (const StatusEvent& e : events)
    if (e.seq >= 0)
      for (auto& a : an) a->on_status(e);
  for (const Block& b : blocks)
    for (auto& a : an) a->on_block(b);
  std::vector<Frd> out;
  for (auto& a : an) {
    a->flush();
    out.push_back(a->frd());
  }
  return out;
}

}  // namespace fralab
