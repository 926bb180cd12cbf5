#include "fralab/analyze/pair_analyzer.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "fralab/analyze/bla.h"
#include "fralab/analyze/fourier_filter.h"
#include "fralab/analyze/period_fft.h"
#include "fralab/analyze/repeats.h"

namespace fralab {

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
  std::tie(e1_, e2_) = split_pair(pair);
  for (const std::string& ch : {e1_, e2_, std::string("ref_phase")}) store_->keep(ch);
  reader_ = store_->add_reader();
}

PairAnalyzer::~PairAnalyzer() { store_->remove_reader(reader_); }

const double* PairAnalyzer::samples(const std::string& ch, int64_t n) const {
  return store_->channel(ch)->data() + (n - store_->base());
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
    const std::string base = ch.rfind("u_", 0) == 0 ? ch.substr(2) : ch;
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

// An orthogonal multisine's lines: unique, ascending, within 1..P/2-1 (what a period resolves).
static std::vector<int> orthogonal_lines(const StatusEvent& st) {
  std::set<int> uniq;
  for (int k : st.lines)
    if (k >= 1 && k < st.period_samples / 2) uniq.insert(k);
  return {uniq.begin(), uniq.end()};
}

// The nearest line no input excites on each side of line k (at most two), within 1..P/2-1.
static std::vector<int> unexcited_neighbours(const std::vector<bool>& excited, int k, int P) {
  std::vector<int> out;
  for (int dir : {-1, 1})
    for (int kk = k + dir; kk >= 1 && kk < P / 2; kk += dir)
      if (!excited[kk]) {
        out.push_back(kk);
        break;
      }
  return out;
}

// sum_p |z_p - mean_p z|^2 over the M periods: the spread of a line's period values about their
// mean (a periodic part, distortion or the response itself, cancels in it).
template <class Z>
static double period_spread(int M, const Z& z) {
  std::complex<double> zm = 0;
  for (int p = 0; p < M; ++p) zm += z(p);
  zm /= double(M);
  double s = 0;
  for (int p = 0; p < M; ++p) s += std::norm(z(p) - zm);
  return s;
}

// A point's sigma, > 0 as the contract needs: noise-free periods repeat exactly and spread by 0.
static double positive_sigma(double sigma, double mag) {
  return sigma > 0 ? sigma : 1e-300 + 1e-15 * mag;
}

static std::pair<std::string, double> first_excited(const StatusEvent& st) {
  for (size_t i = 0; i < st.inputs.size() && i < st.amplitudes.size(); ++i) {
    if (st.amplitudes[i] > 0.0) return {st.inputs[i], st.amplitudes[i]};
  }
  return {"", 0.0};
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
      for (const std::string& ch : {"u_" + st.inputs[i], st.inputs[i]}) store_->keep(ch);
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
      Experiment ex;
      if (ready) {
        ex = orthogonal_experiment(it->second);
      } else {
        ex.valid = false;
        ex.note = "incomplete window: " + describe_gaps(a, b);
      }
      for (const FrdPoint& q : add_experiment(it->second, std::move(ex))) {
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
  for (auto& [r, g] : groups_) {
    const int nu = int(g.ins.size());
    std::string missing;
    for (int e = 0; e < nu; ++e)
      if (!g.experiments.count(e)) missing += (missing.empty() ? "" : ", ") + std::to_string(e + 1);
    FrdPoint p;
    p.step = r * nu;
    p.valid = false;
    p.input = first_excited(g.st).first;
    p.note = "orthogonal multisine realisation " + std::to_string(r + 1) + ": experiment(s) " +
             missing + " of " + std::to_string(nu) +
             " never arrived (their status is not on the tape)";
    points_.push_back(p);
    fresh_.push_back(p);
  }
  groups_.clear();
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
  std::vector<Complex> b1(K), b2(K);
  for (int k = 0; k < K; ++k) {
    size_t s = L * k / K, e = L * (k + 1) / K;
    b1[k] = fourier_phasor(d1.data(), ref, s, e);
    b2[k] = fourier_phasor(d2.data(), ref, s, e);
  }
  double se = 0, s11 = 0, s22 = 0;
  Complex s12 = 0;
  for (int k = 0; k < K; ++k) {
    se += std::norm(b2[k] - r * b1[k]);
    s11 += std::norm(b1[k]);
    s22 += std::norm(b2[k]);
    s12 += std::conj(b1[k]) * b2[k];
  }
  p.sigma = std::sqrt(se / (double(K) * (K - 1))) / std::abs(p1);
  p.coherence = (s11 > 0 && s22 > 0) ? std::norm(s12) / (s11 * s22) : 0.0;
  for (int h : {2, 3}) {
    Reference rh = reference(h);
    double rel = std::abs(fourier_phasor(d2.data(), rh, 0, L)) / std::max(std::abs(p2), 1e-300);
    (h == 2 ? p.h2_rel : p.h3_rel) = rel;
  }
  return p;
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
      if (ch == st.inputs[i] || ch == "u_" + st.inputs[i]) want = int(i);
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
    if (std::abs(m1) == 0.0 || !std::isfinite(std::abs(m1)) || !std::isfinite(std::abs(m2))) {
      q.valid = false;
      q.note = "channel " + e1_ + " has no component at line " + std::to_string(k);
      out.push_back(q);
      continue;
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
    if (e1_ == "u_" + q.input) q.line_amplitude = 2 * std::abs(m1) / P;
    q.coherence = std::norm(s12) / (s11 * s22);
    double lvl = 0;
    for (int kk : nb) {
      std::complex<double> v = 0;
      for (int p = 0; p < M; ++p) v += X2[p][kk];
      lvl += std::abs(v / double(M));
    }
    q.nl_rel = nb.empty() ? 0.0 : lvl / double(nb.size()) / std::max(std::abs(m2), 1e-300);
    out.push_back(q);
  }
  return out;
}

PairAnalyzer::Experiment PairAnalyzer::orthogonal_experiment(const Window& win) {
  const StatusEvent& st = win.st;
  Experiment ex;
  const int P = st.period_samples;
  const int M = P > 0 ? int(st.n_samples / P) : 0;
  const std::vector<int>& ins = win.ins;
  if (P < 4 || M < 2) {
    ex.valid = false;
    ex.note = "multisine status without periods or lines";
    return ex;
  }
  auto channel = [&](const std::string& ch) -> const double* {
    const std::vector<double>* v = store_->channel(ch);
    if (!v || st.sample - store_->base() + st.n_samples > int64_t(v->size())) return nullptr;
    const double* c = samples(ch, st.sample);
    for (int64_t k = 0; k < st.n_samples; ++k)
      if (std::isnan(c[k])) return nullptr;
    return c;
  };
  std::vector<const double*> u, pos;
  for (int i : ins) {
    const std::string& name = st.inputs[i];
    u.push_back(channel("u_" + name));
    pos.push_back(channel(name));
    if (!u.back() || !pos.back()) {
      ex.valid = false;
      ex.note = "orthogonal multisine: the tape has no channel " + (u.back() ? name : "u_" + name) +
                " over the window (the analyser solves with every input's command and position)";
      return ex;
    }
  }
  const std::vector<int> lines = orthogonal_lines(st);
  std::vector<bool> excited(P / 2 + 1, false);
  for (int k : lines)
    if (k >= 0 && k <= P / 2) excited[k] = true;
  PeriodFft fft(P);
  auto period_spectrum = [&](const double* x, int p) { return fft(x + size_t(p) * P); };
  const size_t L = lines.size();
  ex.x1.assign(L, std::vector<Complex>(M));
  ex.x2.assign(L, std::vector<Complex>(M));
  // The nearest non-excited line each side of every line (pooled noise).
  std::vector<std::vector<int>> nbk(L);
  for (size_t j = 0; j < L; ++j) nbk[j] = unexcited_neighbours(excited, lines[j], P);
  ex.nb1.assign(L, {});
  ex.nb2.assign(L, {});
  for (size_t j = 0; j < L; ++j) {
    ex.nb1[j].assign(nbk[j].size(), std::vector<Complex>(M));
    ex.nb2[j].assign(nbk[j].size(), std::vector<Complex>(M));
  }
  ex.u.assign(L, std::vector<Complex>(ins.size(), 0.0));
  ex.pos.assign(L, std::vector<Complex>(ins.size(), 0.0));
  ex.nl.assign(L, 0.0);
  std::vector<Complex> x2_mean(P / 2 + 1, 0.0);
  std::vector<std::vector<Complex>> pos_mean(ins.size(), std::vector<Complex>(P / 2 + 1, 0.0));
  // [input q][line j][line, then its neighbours][period]: the positions per period, for their
  // noise.
  std::vector<std::vector<std::vector<std::vector<Complex>>>> posp(ins.size());
  for (auto& pq : posp) {
    pq.resize(L);
    for (size_t j = 0; j < L; ++j) pq[j].assign(1 + nbk[j].size(), std::vector<Complex>(M));
  }
  const double* a = samples(e1_, st.sample);
  const double* b = samples(e2_, st.sample);
  for (int p = 0; p < M; ++p) {
    const auto s1 = period_spectrum(a, p);
    const auto s2 = period_spectrum(b, p);
    for (size_t j = 0; j < L; ++j) {
      ex.x1[j][p] = s1[lines[j]];
      ex.x2[j][p] = s2[lines[j]];
      for (size_t n = 0; n < nbk[j].size(); ++n) {
        ex.nb1[j][n][p] = s1[nbk[j][n]];
        ex.nb2[j][n][p] = s2[nbk[j][n]];
      }
    }
    for (size_t k = 0; k < x2_mean.size(); ++k) x2_mean[k] += s2[k] / double(M);
    for (size_t q = 0; q < ins.size(); ++q) {
      const auto su = period_spectrum(u[q], p);
      for (size_t j = 0; j < L; ++j) ex.u[j][q] += su[lines[j]] / double(M);
      const auto sp = period_spectrum(pos[q], p);
      for (size_t k = 0; k < sp.size(); ++k) pos_mean[q][k] += sp[k] / double(M);
      for (size_t j = 0; j < L; ++j) {
        posp[q][j][0][p] = sp[lines[j]];
        for (size_t n = 0; n < nbk[j].size(); ++n) posp[q][j][1 + n][p] = sp[nbk[j][n]];
      }
    }
  }
  // A channel's mean level on line j's unexcited neighbours, relative to line j.
  auto distortion = [&](const std::vector<Complex>& x, size_t j) {
    double lvl = 0;
    for (int kk : nbk[j]) lvl += std::abs(x[kk]);
    return nbk[j].empty() ? 0.0
                          : lvl / double(nbk[j].size()) / std::max(std::abs(x[lines[j]]), 1e-300);
  };
  for (size_t j = 0; j < L; ++j) ex.nl[j] = distortion(x2_mean, j);
  ex.pos_nl.assign(ins.size(), 0.0);
  ex.pos_var.assign(L, std::vector<double>(ins.size(), 0.0));
  for (size_t q = 0; q < ins.size(); ++q) {
    std::vector<double> d(L);
    for (size_t j = 0; j < L; ++j) {
      ex.pos[j][q] = pos_mean[q][lines[j]];
      double ss = 0;
      for (const std::vector<Complex>& v : posp[q][j])
        ss += period_spread(M, [&](int p) { return v[size_t(p)]; });
      ex.pos_var[j][q] = ss / (double(posp[q][j].size()) * double(M) * (M - 1));
      d[j] = distortion(pos_mean[q], j);
    }
    std::nth_element(d.begin(), d.begin() + L / 2, d.end());
    ex.pos_nl[q] = L ? d[L / 2] : 0.0;
  }
  return ex;
}

std::vector<FrdPoint> PairAnalyzer::add_experiment(const Window& win, Experiment ex) {
  const StatusEvent& st = win.st;
  const int r = st.step / int(win.ins.size()), e = st.step % int(win.ins.size());
  Group& g = groups_[r];
  if (g.experiments.empty()) g.st = st, g.ins = win.ins;
  // Every experiment of a realisation must state the same design (a corrupt status may not).
  if (st.step < 0 || st.lines != g.st.lines || st.line_input != g.st.line_input ||
      st.inputs != g.st.inputs || st.period_samples != g.st.period_samples) {
    ex.valid = false;
    ex.note =
        "its status states another design than experiment 1's (step, lines, inputs or "
        "period)";
  }
  g.experiments[e] = std::move(ex);
  for (int k = 0; k < int(g.ins.size()); ++k)
    if (!g.experiments.count(k)) return {};
  // The realisation is complete (experiments 0..n_u-1 of its first status's design): solve per
  // line.
  Group grp = std::move(g);
  groups_.erase(r);
  const std::vector<int>& ins = grp.ins;
  const int nu = int(ins.size());
  const std::vector<int> lines = orthogonal_lines(grp.st);
  const double df = grp.st.sample_rate_hz / grp.st.period_samples;
  auto name = [&](int q) { return grp.st.inputs[ins[q]]; };
  // The pair's input(s): the one named by E1 or E2 (u_X or X); none: every input.
  std::vector<int> want;
  for (int q = 0; q < nu; ++q)
    for (const std::string& ch : {e1_, e2_})
      if ((ch == name(q) || ch == "u_" + name(q)) &&
          std::find(want.begin(), want.end(), q) == want.end())
        want.push_back(q);
  if (want.empty())
    for (int q = 0; q < nu; ++q) want.push_back(q);
  std::string bad;
  for (const auto& [ee, x] : grp.experiments)
    if (!x.valid)
      bad += (bad.empty() ? "" : "; ") + ("experiment " + std::to_string(ee + 1) + ": " + x.note);
  // Regressors: every input's command, except that for a pair X:O an input whose position
  // distorts enters by its measured position.
  const auto& gin = grp.st.inputs;
  const bool position_pair = std::find(gin.begin(), gin.end(), e1_) != gin.end();
  std::vector<bool> by_position(nu, false);
  if (position_pair && bad.empty()) {
    for (int q = 0; q < nu; ++q) {
      double d = 0;
      for (const auto& [ee, x] : grp.experiments) d += x.pos_nl[q] / nu;
      by_position[q] = d > opt_.distortion_threshold;
    }
  }
  std::vector<FrdPoint> out;
  for (size_t j = 0; j < lines.size(); ++j) {
    for (int q : want) {
      FrdPoint p;
      p.w = 2 * std::numbers::pi * lines[j] * df;
      p.step = r * nu;
      p.input = name(q);
      p.amplitude = size_t(ins[q]) < grp.st.amplitudes.size() ? grp.st.amplitudes[ins[q]] : 0.0;
      if (!bad.empty()) {
        p.valid = false;
        p.note = "orthogonal multisine realisation " + std::to_string(r + 1) + ": " + bad;
        out.push_back(p);
        continue;
      }
      p.n_cycles = int(grp.experiments.begin()->second.x1[j].size());
      Eigen::MatrixXcd U(nu, nu);
      Eigen::VectorXcd X1(nu), X2(nu);
      for (int ee = 0; ee < nu; ++ee) {
        const Experiment& x = grp.experiments.at(ee);
        for (int qq = 0; qq < nu; ++qq) U(qq, ee) = by_position[qq] ? x.pos[j][qq] : x.u[j][qq];
        const int M = int(x.x1[j].size());
        Complex m1 = 0, m2 = 0;
        for (int pp = 0; pp < M; ++pp) m1 += x.x1[j][pp], m2 += x.x2[j][pp];
        X1(ee) = m1 / double(M);
        X2(ee) = m2 / double(M);
      }
      Eigen::JacobiSVD<Eigen::MatrixXcd> svd(U);
      const auto sv = svd.singularValues();
      if (!(sv(nu - 1) > 1e-9 * sv(0))) {
        p.valid = false;
        p.note = "orthogonal multisine: the commands do not span the " + std::to_string(nu) +
                 " inputs at line " + std::to_string(lines[j]) + " (singular input matrix)";
        out.push_back(p);
        continue;
      }
      const Eigen::MatrixXcd Ui = U.inverse();  // h = X U^{-1}: h_q = sum_e X_e Ui(e, q)
      const Complex h1 = X1.transpose() * Ui.col(q), h2 = X2.transpose() * Ui.col(q);
      if (std::abs(h1) == 0.0 || !std::isfinite(std::abs(h1)) || !std::isfinite(std::abs(h2))) {
        p.valid = false;
        p.note = "channel " + e1_ + " has no response to input " + p.input + " at line " +
                 std::to_string(lines[j]);
        out.push_back(p);
        continue;
      }
      const Complex R = h2 / h1;
      // Every input's coefficient in both channels (the positions' noise term below).
      const Eigen::RowVectorXcd d = X2.transpose() * Ui - R * (X1.transpose() * Ui);
      p.mag = std::abs(R);
      p.phase_deg = std::arg(R) * 180 / std::numbers::pi;
      double var = 0, nl = 0;
      for (int ee = 0; ee < nu; ++ee) {
        const Experiment& x = grp.experiments.at(ee);
        const int M = int(x.x1[j].size());
        // The spread over periods of z = X2 - R X1 at the line and its unexcited neighbours.
        auto spread = [&](const std::vector<Complex>& v1, const std::vector<Complex>& v2) {
          return period_spread(M, [&](int pp) { return v2[size_t(pp)] - R * v1[size_t(pp)]; });
        };
        double sz = spread(x.x1[j], x.x2[j]);
        for (size_t n = 0; n < x.nb1[j].size(); ++n) sz += spread(x.nb1[j][n], x.nb2[j][n]);
        var += std::norm(Ui(ee, q)) * sz / (double(1 + x.nb1[j].size()) * double(M) * (M - 1));
        for (int rr = 0; rr < nu; ++rr)
          if (by_position[rr]) var += std::norm(Ui(ee, q)) * std::norm(d(rr)) * x.pos_var[j][rr];
        nl += x.nl[j] / nu;
      }
      p.sigma = positive_sigma(std::sqrt(var) / std::abs(h1), p.mag);
      p.coherence = std::norm(R) / (std::norm(R) + double(nu) * p.n_cycles * p.sigma * p.sigma);
      p.nl_rel = nl;
      double ua = 0;
      for (int ee = 0; ee < nu; ++ee)
        ua += 2 * std::abs(grp.experiments.at(ee).u[j][q]) / grp.st.period_samples / nu;
      p.line_amplitude = ua;
      out.push_back(p);
    }
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
