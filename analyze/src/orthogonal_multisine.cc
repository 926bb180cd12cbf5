#include "orthogonal_multisine.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "fralab/analyze/period_fft.h"
#include "fralab/core/pair_id.h"
#include "line_statistics.h"

namespace fralab::analyze_detail {

using Complex = std::complex<double>;

namespace {

// A channel's mean level on line j's unexcited neighbours nbk[j], relative to line j (x: its
// period-mean spectrum).
double distortion(const std::vector<Complex>& x, const std::vector<int>& lines,
                  const std::vector<std::vector<int>>& nbk, size_t j) {
  double lvl = 0;
  for (int kk : nbk[j]) lvl += std::abs(x[kk]);
  return nbk[j].empty() ? 0.0
                        : lvl / double(nbk[j].size()) / std::max(std::abs(x[lines[j]]), 1e-300);
}

// From the period spectra gathered: E2's distortion per line (ex.nl), and per input its
// position's period mean at each line (ex.pos), that mean's variance pooled over the line and its
// neighbours (ex.pos_var) and the median over lines of its distortion (ex.pos_nl).
void distortion_and_position_noise(
    const std::vector<int>& lines, const std::vector<std::vector<int>>& nbk,
    const std::vector<Complex>& x2_mean, const std::vector<std::vector<Complex>>& pos_mean,
    const std::vector<std::vector<std::vector<std::vector<Complex>>>>& posp, int M,
    OrthogonalExperiment& ex) {
  const size_t L = lines.size(), nu = pos_mean.size();
  for (size_t j = 0; j < L; ++j) ex.nl[j] = distortion(x2_mean, lines, nbk, j);
  ex.pos_nl.assign(nu, 0.0);
  ex.pos_var.assign(L, std::vector<double>(nu, 0.0));
  for (size_t q = 0; q < nu; ++q) {
    std::vector<double> d(L);
    for (size_t j = 0; j < L; ++j) {
      ex.pos[j][q] = pos_mean[q][lines[j]];
      double ss = 0;
      for (const std::vector<Complex>& v : posp[q][j])
        ss += period_spread(M, [&](int p) { return v[size_t(p)]; });
      ex.pos_var[j][q] = ss / (double(posp[q][j].size()) * double(M) * (M - 1));
      d[j] = distortion(pos_mean[q], lines, nbk, j);
    }
    std::nth_element(d.begin(), d.begin() + L / 2, d.end());
    ex.pos_nl[q] = L ? d[L / 2] : 0.0;
  }
}

}  // namespace

OrthogonalExperiment orthogonal_experiment(const StatusEvent& st, const std::vector<int>& ins,
                                           const double* a, const double* b,
                                           const WindowChannel& channel) {
  OrthogonalExperiment ex;
  const int P = st.period_samples;
  const int M = P > 0 ? int(st.n_samples / P) : 0;
  if (P < 4 || M < 2) {
    ex.valid = false;
    ex.note = "multisine status without periods or lines";
    return ex;
  }
  std::vector<const double*> u, pos;
  for (int i : ins) {
    const std::string& name = st.inputs[i];
    u.push_back(channel(command_channel(name)));
    pos.push_back(channel(name));
    if (!u.back() || !pos.back()) {
      ex.valid = false;
      ex.note = "orthogonal multisine: the tape has no channel " +
                (u.back() ? name : command_channel(name)) +
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
  distortion_and_position_noise(lines, nbk, x2_mean, pos_mean, posp, M, ex);
  return ex;
}

namespace {

// The point of input q at line j (of `lines`) from a realisation's complete experiments: the
// input matrix U (commands, or positions where by_position), h = X U^{-1}, R = h2_q / h1_q and
// its sigma, coherence, nl_rel and line amplitude (pair_analyzer.h). p holds the point's w, step,
// input and amplitude; e1 names E1 in a note.
FrdPoint line_point(FrdPoint p, const std::map<int, OrthogonalExperiment>& experiments, size_t j,
                    int line, int q, const std::vector<bool>& by_position, int period_samples,
                    const std::string& e1) {
  const int nu = int(by_position.size());
  p.n_cycles = int(experiments.begin()->second.x1[j].size());
  Eigen::MatrixXcd U(nu, nu);
  Eigen::VectorXcd X1(nu), X2(nu);
  for (int ee = 0; ee < nu; ++ee) {
    const OrthogonalExperiment& x = experiments.at(ee);
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
             " inputs at line " + std::to_string(line) + " (singular input matrix)";
    return p;
  }
  const Eigen::MatrixXcd Ui = U.inverse();  // h = X U^{-1}: h_q = sum_e X_e Ui(e, q)
  const Complex h1 = X1.transpose() * Ui.col(q), h2 = X2.transpose() * Ui.col(q);
  if (std::abs(h1) == 0.0 || !std::isfinite(std::abs(h1)) || !std::isfinite(std::abs(h2))) {
    p.valid = false;
    p.note = "channel " + e1 + " has no response to input " + p.input + " at line " +
             std::to_string(line);
    return p;
  }
  const Complex R = h2 / h1;
  // Every input's coefficient in both channels (the positions' noise term below).
  const Eigen::RowVectorXcd d = X2.transpose() * Ui - R * (X1.transpose() * Ui);
  p.mag = std::abs(R);
  p.phase_deg = std::arg(R) * 180 / std::numbers::pi;
  double var = 0, nl = 0;
  for (int ee = 0; ee < nu; ++ee) {
    const OrthogonalExperiment& x = experiments.at(ee);
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
    ua += 2 * std::abs(experiments.at(ee).u[j][q]) / period_samples / nu;
  p.line_amplitude = ua;
  return p;
}

}  // namespace

OrthogonalRealisations::OrthogonalRealisations(std::string e1, std::string e2,
                                               double distortion_threshold)
    : e1_(std::move(e1)), e2_(std::move(e2)), distortion_threshold_(distortion_threshold) {}

std::vector<FrdPoint> OrthogonalRealisations::add(const StatusEvent& st,
                                                  const std::vector<int>& ins,
                                                  OrthogonalExperiment ex) {
  const int r = st.step / int(ins.size()), e = st.step % int(ins.size());
  Group& g = groups_[r];
  if (g.experiments.empty()) g.st = st, g.ins = ins;
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
  // The realisation is complete (experiments 0..n_u-1 of its first status's design).
  const Group grp = std::move(g);
  groups_.erase(r);
  return solve(r, grp);
}

// The pair's input(s): the one named by E1 or E2 (u_X or X); none: every input.
std::vector<int> OrthogonalRealisations::wanted_inputs(const Group& grp) const {
  const int nu = int(grp.ins.size());
  auto name = [&](int q) { return grp.st.inputs[grp.ins[q]]; };
  std::vector<int> want;
  for (int q = 0; q < nu; ++q)
    for (const std::string& ch : {e1_, e2_})
      if ((ch == name(q) || ch == command_channel(name(q))) &&
          std::find(want.begin(), want.end(), q) == want.end())
        want.push_back(q);
  if (want.empty())
    for (int q = 0; q < nu; ++q) want.push_back(q);
  return want;
}

// Regressors: every input's command, except that for a pair X:O an input whose position distorts
// (its mean over experiments above the threshold) enters by its measured position.
std::vector<bool> OrthogonalRealisations::inputs_by_position(const Group& grp) const {
  const int nu = int(grp.ins.size());
  const auto& gin = grp.st.inputs;
  const bool position_pair = std::find(gin.begin(), gin.end(), e1_) != gin.end();
  std::vector<bool> by_position(nu, false);
  if (!position_pair) return by_position;
  for (int q = 0; q < nu; ++q) {
    double d = 0;
    for (const auto& [ee, x] : grp.experiments) d += x.pos_nl[q] / nu;
    by_position[q] = d > distortion_threshold_;
  }
  return by_position;
}

std::vector<FrdPoint> OrthogonalRealisations::solve(int r, const Group& grp) const {
  const std::vector<int>& ins = grp.ins;
  const int nu = int(ins.size());
  const std::vector<int> lines = orthogonal_lines(grp.st);
  const double df = grp.st.sample_rate_hz / grp.st.period_samples;
  std::string bad;
  for (const auto& [ee, x] : grp.experiments)
    if (!x.valid)
      bad += (bad.empty() ? "" : "; ") + ("experiment " + std::to_string(ee + 1) + ": " + x.note);
  const std::vector<bool> by_position =
      bad.empty() ? inputs_by_position(grp) : std::vector<bool>(nu, false);
  const std::vector<int> want = wanted_inputs(grp);
  std::vector<FrdPoint> out;
  for (size_t j = 0; j < lines.size(); ++j) {
    for (int q : want) {
      FrdPoint p;
      p.w = 2 * std::numbers::pi * lines[j] * df;
      p.step = r * nu;
      p.input = grp.st.inputs[ins[q]];
      p.amplitude = size_t(ins[q]) < grp.st.amplitudes.size() ? grp.st.amplitudes[ins[q]] : 0.0;
      if (!bad.empty()) {
        p.valid = false;
        p.note = "orthogonal multisine realisation " + std::to_string(r + 1) + ": " + bad;
        out.push_back(p);
        continue;
      }
      out.push_back(
          line_point(p, grp.experiments, j, lines[j], q, by_position, grp.st.period_samples, e1_));
    }
  }
  return out;
}

std::vector<FrdPoint> OrthogonalRealisations::incomplete() {
  std::vector<FrdPoint> out;
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
    out.push_back(p);
  }
  groups_.clear();
  return out;
}

}  // namespace fralab::analyze_detail
