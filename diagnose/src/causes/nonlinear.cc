#include "nonlinear.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "cause.h"
#include "fralab/plant/nonlinearity.h"

namespace fralab::diag {

C nl_describing_function(CauseKind kind, double width, double y) {
  const bool backlash = kind == CauseKind::kHysteresis;
  auto out_amp = [&](double a) {
    return backlash ? std::abs(backlash_describing_function(a, width)) * a
                    : deadband_describing_function(a, width) * a;
  };
  double lo = width / 2, hi = width / 2 + 2 * y + 1e-12;
  while (out_amp(hi) < y) hi *= 2;
  for (int i = 0; i < 80; ++i) {
    double m = (lo + hi) / 2;
    (out_amp(m) < y ? lo : hi) = m;
  }
  const double a = (lo + hi) / 2;
  return backlash ? backlash_describing_function(a, width)
                  : C(deadband_describing_function(a, width), 0);
}

bool fits_by_multisine(const PairFit& p) {
  if (!p.ms || p.w.empty() || !std::is_sorted(p.w.begin(), p.w.end())) return false;
  for (double w : p.w)
    if (!std::binary_search(p.ms->w.begin(), p.ms->w.end(), w)) return false;
  return true;
}

std::vector<C> nonlinear_factor(const PairFit& p, CauseKind kind, double width,
                                const std::vector<C>& lin, std::vector<double>* var_nl) {
  const size_t N = p.w.size();
  std::vector<C> F(N, 1.0);
  const bool backlash = kind == CauseKind::kHysteresis;
  if (fits_by_multisine(p)) {
    // The element's input on every line of the multisine: |sim lin| at p's points, interpolated
    // in log w between them on the lines p does not use (held beyond its ends).
    const std::vector<double>& lw = p.ms->w;
    std::vector<double> gain(lw.size());
    for (size_t j = 0; j < lw.size(); ++j) {
      const size_t hi = size_t(std::lower_bound(p.w.begin(), p.w.end(), lw[j]) - p.w.begin());
      auto g = [&](size_t q) { return std::abs(p.sim[q] * lin[q]); };
      if (hi < N && p.w[hi] == lw[j]) {
        gain[j] = g(hi);
      } else if (hi == 0 || hi == N) {
        gain[j] = g(hi == 0 ? 0 : N - 1);
      } else {
        const double t = std::log(lw[j] / p.w[hi - 1]) / std::log(p.w[hi] / p.w[hi - 1]);
        gain[j] = g(hi - 1) * (1 - t) + g(hi) * t;
      }
    }
    const MultisineBla& b = p.ms->bla(
        NonlinearitySpec{backlash ? NonlinearityKind::kHysteresis : NonlinearityKind::kDeadband,
                         width},
        gain);
    if (var_nl) var_nl->assign(N, 0.0);
    for (size_t q = 0; q < N; ++q) {
      const size_t j = size_t(std::lower_bound(lw.begin(), lw.end(), p.w[q]) - lw.begin());
      F[q] = b.g[j];
      if (var_nl) (*var_nl)[q] = b.var_nl[j];
    }
    return F;
  }
  for (size_t q = 0; q < N; ++q)
    F[q] = nl_describing_function(kind, width, p.amp[q] * std::abs(p.meas[q]));
  if (var_nl) var_nl->assign(N, 0.0);
  return F;
}

Cause fit_nonlinearity(const PairFit& p, const std::vector<size_t>& low, const std::vector<C>& base,
                       const std::vector<C>& lin, double* c0) {
  const size_t N = p.w.size();
  Cause best;
  auto low_chi2 = [&](const std::vector<C>& f) {
    double c = 0;
    for (size_t q : low)
      c += std::norm(p.meas[q] - p.sim[q] * base[q] * lin[q] * f[q]) / (p.sig[q] * p.sig[q]);
    return c;
  };
  for (CauseKind kind : {CauseKind::kHysteresis, CauseKind::kDeadband}) {
    auto F = [&](double width) { return nonlinear_factor(p, kind, width, lin); };
    const double a = p.amp[low[0]];
    double width = minimise_1d([&](double x) { return low_chi2(F(x)); }, 1e-4 * a, 1.9 * a, 200);
    double c = low_chi2(F(width));
    if (c < best.chi2) best = Cause{kind, {{Param::kWidth, width}}, F(width), c, 1, ""};
  }
  *c0 = low_chi2(std::vector<C>(N, 1.0));
  return best;
}

std::string explain_nonlinearity(const PairFit& p, const Cause& nl, const std::vector<size_t>& low,
                                 double mean_h3, double corner_rad_s, double low_fraction) {
  constexpr double kPi = std::numbers::pi;
  std::ostringstream ex;
  const C n0 = nl.F[low[0]];
  if (fits_by_multisine(p)) {
    ex << "distortion on the non-excited lines (median " << fmt(100 * mean_h3, 2)
       << " % of the line); the best linear approximation of a " << to_string(nl.cause)
       << " of width " << fmt(nl.params.at(Param::kWidth), 3) << " under the multisine ("
       << p.w.size() << " lines at " << fmt(p.ms->amplitude[0], 3)
       << " each) passes the lowest line with gain " << fmt(std::abs(n0), 3) << " and lag "
       << fmt(-std::arg(n0) * 180 / kPi, 3) << " deg, the highest with gain "
       << fmt(std::abs(nl.F.back()), 3) << " and lag " << fmt(-std::arg(nl.F.back()) * 180 / kPi, 3)
       << " deg";
    return ex.str();
  }
  ex << "odd harmonics in the position (3rd at " << fmt(100 * mean_h3, 2)
     << " % of the fundamental); below " << fmt(low_fraction * corner_rad_s / (2 * kPi), 2)
     << " Hz the actuator lags " << fmt(-std::arg(n0) * 180 / kPi, 3) << " deg with gain "
     << fmt(std::abs(n0), 3) << " at +-" << fmt(p.amp[low[0]], 3) << " (describing function of a "
     << to_string(nl.cause) << " of width " << fmt(nl.params.at(Param::kWidth), 3) << ")";
  return ex.str();
}

namespace {

// hysteresis and deadband as causes: an element in the actuator of the finding's input, of
// `width` in input units, which the simulation lacks (its primary parameter, a positive scale).
// The explanation is written when fitted (explain_nonlinearity).
class Nonlinearity final : public CauseUnit {
 public:
  Nonlinearity(CauseKind kind, const char* name) : kind_(kind), name_(name) {}
  CauseKind kind() const override { return kind_; }
  const char* name() const override { return name_; }
  PrimaryParameter primary_parameter(const Finding&) const override {
    return {Param::kWidth, std::nullopt};
  }
  IntervalDomain interval_domain() const override { return {true, 1e-6}; }
  void apply(Model& m, const Finding& f) const override {
    m.inputs[m.input_index(f.input)].nonlinearity.push_back({kind_ == CauseKind::kHysteresis
                                                                 ? NonlinearityKind::kHysteresis
                                                                 : NonlinearityKind::kDeadband,
                                                             f.parameters.at(Param::kWidth)});
  }
  std::string explain(const Finding& f) const override { return f.explanation; }

 private:
  CauseKind kind_;
  const char* name_;
};

}  // namespace

const CauseUnit& hysteresis_cause() {
  static const Nonlinearity c(CauseKind::kHysteresis, "hysteresis");
  return c;
}

const CauseUnit& deadband_cause() {
  static const Nonlinearity c(CauseKind::kDeadband, "deadband");
  return c;
}

}  // namespace fralab::diag
