// TFNS identification (tfns.h): the data's preparation and the result's figures shared by fit_tf
// and refine_tf, and fit_tf as a driver of its steps; the method is docs/method/identifier.md. The
// steps live in files of their own: the noise level without sigma (noise_estimate.h), the delay
// searches (delay_search.h), the order search (order_search.h), the chosen model's simplification
// (simplify.h); the JSON of a fit is fit_json.cc.
#include "fralab/identify/tfns.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include "delay_search.h"
#include "fit_data.h"
#include "fralab/identify/pole_set_fit.h"
#include "noise_estimate.h"
#include "order_search.h"
#include "output_error.h"

namespace fralab {

using namespace tfns_detail;

namespace {

// Valid points of `pts` into d (sorted by frequency, weights); false with res set when there is
// nothing to fit (too few points, or no response above the measured noise).
bool prepare_data(const std::vector<FrdPoint>& pts, const FitOptions& o, Data& d, FitResult& res) {
  std::vector<FrdPoint> v;
  for (const auto& p : pts)
    if (p.valid && p.w > 0 && std::isfinite(p.mag) && std::isfinite(p.phase_deg)) v.push_back(p);
  std::sort(v.begin(), v.end(), [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  res.n_points = int(v.size());
  if (v.size() < 3) {
    res.message = "need at least 3 valid points, have " + std::to_string(v.size());
    return false;
  }
  d.has_sigma = o.use_sigma;
  for (const auto& p : v) d.has_sigma = d.has_sigma && p.sigma > 0;
  for (const auto& p : v) {
    d.w.push_back(p.w);
    d.g.push_back(p.value());
    d.sigma.push_back(p.sigma);
    double mag2 = std::max(std::norm(p.value()), 1e-300);
    d.W.push_back(d.has_sigma ? 1.0 / (p.sigma * p.sigma) : 1.0 / mag2);
  }
  if (d.has_sigma) {
    int clear = 0;
    for (const auto& p : v) clear += p.sigma <= 0.3 * p.mag;
    if (clear < 3) {
      res.status = FitResult::Status::kNoResponse;
      res.message = "no response above the noise: " + std::to_string(clear) + " of " +
                    std::to_string(v.size()) + " points measured to better than 30 %";
      return false;
    }
  }
  return true;
}

// The result's figures, roots, Pade sets and sigmas for the chosen model.
void fill_result(FitResult& res, const Data& d, const Tf& tf, bool free_delay, const Score& s,
                 double chi2dof, bool adequate, int iterations, double e_phi, int reflected) {
  res.tf = tf;
  res.num_order = tf.num_order();
  res.den_order = tf.den_order();
  res.iterations = iterations;
  res.e_phi = e_phi;
  res.e_n = s.e_n;
  res.chi2_per_dof = chi2dof;
  std::tie(res.rms_rel_error, res.max_rel_error) = rel_errors(d, tf);
  res.unstable_reflected = reflected;
  res.pade = find_pade_sets(res.tf);
  for (const auto& p : res.pade) res.pade_delay_s += p.delay_s;
  res.zero_info = root_info(res.tf.zeros);
  res.pole_info = root_info(res.tf.poles);
  Sigmas sg = parameter_sigmas(d, res.tf, free_delay, s.sse);
  for (size_t i = 0; i < sg.zeros.size() && i < res.zero_info.size(); ++i)
    res.zero_info[i].rel_sigma = sg.zeros[i];
  for (size_t i = 0; i < sg.poles.size() && i < res.pole_info.size(); ++i)
    res.pole_info[i].rel_sigma = sg.poles[i];
  res.gain_rel_sigma = sg.gain;
  res.delay_sigma_s = sg.delay;
  res.status = adequate ? FitResult::Status::kConverged : FitResult::Status::kNotAdequate;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: order %d/%d, %s %.3g, delay %.4g s, %d SK iterations",
                res.status_str().c_str(), res.num_order, res.den_order,
                d.has_sigma ? "chi2/dof" : "E_N", d.has_sigma ? res.chi2_per_dof : res.e_n,
                res.tf.delay_s, res.iterations);
  res.message = buf;
}

// Step 6b: the order search ran up to its maximum without an adequate order. Either the data
// hold more modes than that maximum, or they scatter more than their sigma (a nonlinearity, a
// sigma too small) and no order is adequate: the lowest chi^2/dof a model reaches tells the
// scatter's level, and the order search's own (at its capped order) overstates it when modes are
// left. So a pole set (vector fitting with adding and skimming) is fitted against the sigma given
// or estimated; the lowest chi^2/dof of it and of the order search's candidates sets the scale;
// the pole set is fitted again with sigma so scaled (its size chosen by the criterion against the
// scatter, as the order search chooses its orders), with the order search's delay, and replaces
// the order search's fit when its
// criterion chi^2 / scale^2 + ln(2N) p is lower. On the J85 lab's command paths through an
// actuator's hysteresis the scale is the scatter's and the order search's fits stand; on an impact
// hammer's 20 light modes the pole set wins.
// The pole set of the data (delay tau removed) judged against the scatter's level: fitted against
// the sigma given (W_given), the lowest chi^2/dof of it and `other_lowest` sets the scale^2, and
// when that exceeds 1 it is fitted again with sigma so scaled. kFailed when either fit fails.
struct ScatterPoleSet {
  PoleSetFit fit;
  double scale2 = 1;
};
ScatterPoleSet pole_set_against_scatter(const Data& d, const std::vector<double>& W_given,
                                        double tau, double other_lowest, const FitOptions& o) {
  ScatterPoleSet out;
  std::vector<C> g = d.g;
  for (size_t i = 0; i < g.size(); ++i) g[i] *= std::polar(1.0, d.w[i] * tau);
  PoleSetFitOptions po;
  po.max_poles = o.max_poles;
  std::vector<double> W = W_given;
  out.fit = fit_pole_set(d.w, {g}, {W}, po);
  if (out.fit.status == PoleSetFit::Status::kFailed) return out;
  out.scale2 = std::max(1.0, std::min(out.fit.chi2_per_dof, other_lowest));
  if (out.scale2 > 1) {
    for (double& x : W) x /= out.scale2;
    out.fit = fit_pole_set(d.w, {g}, {W}, po);
  }
  return out;
}

// A pole set as the fit's result: its figures against the sigma given (d's weights times `given`),
// its status (not adequate: max_order_reached when it holds max_poles), and `note` appended.
void pole_set_result(FitResult& res, const Data& d, const FitOptions& o, const ScatterPoleSet& sp,
                     const Tf& t, bool free_delay, double given, const std::string& note) {
  const Score s = score(d, t);
  const double N = double(d.w.size());
  const int p = n_params(t, free_delay);
  const double chi2dof = s.chi2 * given / std::max(1.0, N - p / 2.0);
  const bool adequate = chi2dof <= (1.0 + 3.0 / std::sqrt(N)) * d.chi2_slack;
  const double noise_rel = res.noise_rel, noise_abs = res.noise_abs;
  fill_result(res, d, t, free_delay, s, chi2dof, adequate, 0, 0, 0);
  res.noise_rel = noise_rel, res.noise_abs = noise_abs;
  res.sigma_scale = adequate ? 1 : std::sqrt(sp.scale2);
  if (!adequate) {
    const std::string was = res.status_str();
    res.status = sp.fit.order >= std::min(o.max_poles, int(d.w.size()) - 2)
                     ? FitResult::Status::kMaxOrderReached
                     : FitResult::Status::kNotAdequate;
    res.message = res.status_str() + res.message.substr(was.size());
  }
  res.message += note;
}

// Step 6b: the order search ran up to its maximum without an adequate order. Either the data
// hold more modes than that maximum, or they scatter more than their sigma (a nonlinearity, a
// sigma too small) and no order is adequate: the lowest chi^2/dof a model reaches tells the
// scatter's level, and the order search's own (at its capped order) overstates it when modes are
// left. So the pole set is judged against the scatter (pole_set_against_scatter, with the order
// search's delay) and replaces the order search's fit when its criterion
// chi^2 / scale^2 + ln(2N) p is lower. On the J85 lab's command paths through an actuator's
// hysteresis the scale is the scatter's and most order search fits stand; on an impact hammer's 20
// light modes the pole set wins.
void prefer_pole_set(FitResult& res, const Data& d, const FitOptions& o, const Tf& chosen,
                     bool free_delay) {
  if (res.status != FitResult::Status::kMaxOrderReached || !d.has_sigma ||
      o.max_poles <= o.max_den_order) {
    return;
  }
  // d's weights are scaled by 1 / sigma_scale^2 when the order was chosen against the scatter.
  const double given = res.sigma_scale * res.sigma_scale;
  std::vector<double> W = d.W;
  for (double& x : W) x *= given;
  // The order search's lowest chi^2/dof: its scale squared when it chose against the scatter.
  const double classic = res.sigma_scale != 1 ? given : res.chi2_per_dof;
  const ScatterPoleSet sp = pole_set_against_scatter(d, W, chosen.delay_s, classic, o);
  if (sp.fit.status == PoleSetFit::Status::kFailed) return;
  Tf t = sp.fit.to_tf(0);
  t.delay_s = chosen.delay_s;
  const Score s = score(d, t), s0 = score(d, chosen);
  const double kappa = std::log(2.0 * double(d.w.size()));
  const int p = n_params(t, free_delay), p0 = n_params(chosen, free_delay);
  const double crit = s.chi2 * given / sp.scale2 + kappa * p;
  const double crit0 = s0.chi2 * given / sp.scale2 + kappa * p0;
  if (!(crit < crit0) || !std::isfinite(s.chi2)) return;
  char buf[360];
  std::snprintf(buf, sizeof buf,
                "; a pole set of %d poles (vector fitting, %d added, %d skimmed; sigma x%.3g) "
                "replaces the order search's %d/%d, which reached its maximum (criterion %.6g "
                "against %.6g)",
                sp.fit.order, sp.fit.added, sp.fit.skimmed, std::sqrt(sp.scale2), res.num_order,
                res.den_order, crit, crit0);
  pole_set_result(res, d, o, sp, t, free_delay, given, buf);
}

// Step 1b: a dense grid (kDenseGrid points or more, with sigma) of more light modes than the order
// search can reach. The pole set, judged against the scatter, is fitted first; when its light pairs
// (zeta < kLightMode) alone need more poles than max_den_order, the order search, which raises the
// order one at a time up to that maximum, could not hold them and is not run (on an impact
// hammer's 3995 lines it took 14 s to reach its maximum and be replaced). A delay is not searched
// on this path: a delay's imitation by poles gives damped pairs, not light ones, and leaves the
// order search to run.
constexpr size_t kDenseGrid = 1000;
constexpr double kLightMode = 0.05;
bool light_modes_first(FitResult& res, const Data& d, const FitOptions& o) {
  if (!d.has_sigma || d.w.size() < kDenseGrid || o.max_poles <= o.max_den_order) return false;
  const ScatterPoleSet sp = pole_set_against_scatter(d, d.W, 0, INFINITY, o);
  if (sp.fit.status == PoleSetFit::Status::kFailed) return false;
  int light = 0;
  for (const C& p : sp.fit.poles)
    if (p.imag() > 0 && -p.real() / std::abs(p) < kLightMode) light += 2;
  if (light <= o.max_den_order) return false;
  const Tf t = sp.fit.to_tf(0);
  char buf[360];
  std::snprintf(buf, sizeof buf,
                "; a pole set of %d poles (vector fitting, %d added, %d skimmed; sigma x%.3g): %d "
                "of them in light pairs (zeta < %.2g), more than the order search's maximum, %d",
                sp.fit.order, sp.fit.added, sp.fit.skimmed, std::sqrt(sp.scale2), light, kLightMode,
                o.max_den_order);
  pole_set_result(res, d, o, sp, t, false, 1.0, buf);
  return true;
}

}  // namespace

void FitOptions::validate() const {
  auto bad = [](const std::string& m) { throw InputError("fit: " + m); };
  if (den_order_start < 0 || num_order_start < 0) bad("starting orders must be >= 0");
  if (num_order_start > den_order_start)
    bad("numerator starting order must be <= denominator starting order");
  if (max_den_order < den_order_start || max_den_order > 30)
    bad("max order must be in [start, 30]");
  if (!(c_phi > 0) || !(c_n > 0)) bad("tolerances c_phi and c_n must be > 0");
  if (max_iterations < 2) bad("max_iterations must be >= 2");
  if (delay == Delay::kFixed && !(delay_s >= 0)) bad("a fixed delay must be >= 0 s");
  if (!(max_delay_s > 0)) bad("max_delay_s must be > 0");
  if (!(tolerance >= 0) || !(noise_floor > 0)) bad("tolerance must be >= 0, noise_floor > 0");
  if (min_num_order < 0) bad("min_num_order must be >= 0");
  if (max_poles < 0 || max_poles > 400) bad("max_poles must be in [0, 400]");
}

std::string FitResult::status_str() const {
  switch (status) {
    case Status::kConverged:
      return "converged";
    case Status::kMaxOrderReached:
      return "max_order_reached";
    case Status::kNoResponse:
      return "no_response";
    case Status::kNotAdequate:
      return "not_adequate";
    default:
      return "failed";
  }
}

std::vector<RootInfo> root_info(const std::vector<Root>& roots) {
  std::vector<RootInfo> v;
  for (const Root& r : roots) {
    RootInfo i;
    i.pair = r.pair;
    if (r.pair) {
      C l = r.locations()[0];
      if (l.imag() < 0) l = std::conj(l);
      i.real = l.real();
      i.imag = l.imag();
      i.wn = r.wn;
      i.zeta = r.zeta;
    } else {
      i.real = r.real;
      i.wn = std::abs(r.real);
      i.zeta = r.real < 0 ? 1.0 : -1.0;
    }
    v.push_back(i);
  }
  return v;
}

std::vector<PadeSet> find_pade_sets(const Tf& tf, double tol) {
  std::vector<PadeSet> out;
  std::vector<bool> used(tf.poles.size(), false);
  for (const Root& z : tf.zeros) {
    const bool rhp = z.pair ? z.zeta < 0 : z.real > 0;
    if (!rhp) continue;
    for (size_t k = 0; k < tf.poles.size(); ++k) {
      const Root& p = tf.poles[k];
      if (used[k] || p.pair != z.pair) continue;
      const double wz = z.pair ? z.wn : z.real, wp = p.pair ? p.wn : -p.real;
      if (std::abs(wz - wp) > tol * wp) continue;
      if (z.pair && std::abs(-z.zeta - p.zeta) > std::max(0.35 * p.zeta, 0.05)) continue;
      // A Pade approximant's pairs are damped (|zeta| >= ~0.04 up to order 8): an undamped pair
      // mirrored onto an undamped zero pair is a spurious dipole, not a delay.
      if (z.pair && (p.zeta < 0.02 || -z.zeta < 0.02)) continue;
      PadeSet s{z, p, z.pair ? 2 * (-z.zeta) / z.wn + 2 * p.zeta / p.wn : 1 / wz + 1 / wp};
      used[k] = true;
      out.push_back(s);
      break;
    }
  }
  return out;
}

// The steps of the method (docs/method/identifier.md): the valid points and their weights; without
// sigma, the noise level the stop rule judges against; the order search over the delay hypotheses;
// the chosen model's simplification; its figures and message.
FitResult fit_tf(const std::vector<FrdPoint>& pts, const FitOptions& opt) {
  opt.validate();
  Data d;
  FitResult res;
  if (!prepare_data(pts, opt, d, res)) return res;
  // The delay is searched only where the grid resolves it (otherwise an identical copy of the
  // options: the same fit to the bit).
  FitOptions o = opt;
  const double ambiguity = delay_ambiguity(d.w);
  const bool bounded = o.delay == FitOptions::Delay::kAuto && ambiguity < o.max_delay_s;
  if (bounded) o.max_delay_s = ambiguity;
  d.max_delay = o.max_delay_s;
  DelaySearch delays(d, o);
  if (!d.has_sigma && (o.estimate_noise || o.tolerance > 0) && !estimate_noise(d, o, delays, res))
    return res;
  if (light_modes_first(res, d, o)) {
    res.message += noise_note(res);
    return res;
  }
  OrderSearch search(d, o, delays, res.noise_rel >= 0);
  if (!search.choose_model()) {
    res.message = "no order from " + std::to_string(o.den_order_start) + " to " +
                  std::to_string(search.max_order()) + " could be fitted";
    return res;
  }
  if (o.refine) search.simplify();
  const Candidate& fit = search.chosen();
  fill_result(res, d, fit.tf, fit.free_delay, fit.s, fit.chi2dof, search.passes(), fit.iterations,
              fit.e_phi, fit.reflected);
  search.annotate(res);
  prefer_pole_set(res, d, o, fit.tf, fit.free_delay);
  if (bounded) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "; delay searched up to %.4g s, the grid's ambiguity (2 pi / its median spacing)",
                  ambiguity);
    res.message += buf;
  }
  res.message += noise_note(res);
  return res;
}

FitResult refine_tf(const std::vector<FrdPoint>& pts, const Tf& start, const FitOptions& o) {
  o.validate();
  Data d;
  FitResult res;
  if (!prepare_data(pts, o, d, res)) return res;
  d.max_delay = o.max_delay_s;
  Tf t = start;
  const bool free_delay = o.delay == FitOptions::Delay::kAuto;
  if (o.delay == FitOptions::Delay::kFixed) t.delay_s = o.delay_s;
  if (o.delay == FitOptions::Delay::kNone) t.delay_s = 0;
  if (o.refine) t = refine(d, t, free_delay);
  const Score s = score(d, t);
  double chi2dof = -1;
  const double mf = misfit(d, s, n_params(t, free_delay), o, &chi2dof);
  fill_result(res, d, t, free_delay, s, chi2dof, mf <= 1.0, 0, 0, 0);
  return res;
}

}  // namespace fralab
