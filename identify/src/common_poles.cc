#include "fralab/identify/common_poles.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fralab/core/error.h"

namespace fralab {

using C = std::complex<double>;

double second_difference_noise(const std::vector<C>& g) {
  if (g.size() < 3) return -1;
  std::vector<double> d2;
  for (size_t i = 1; i + 1 < g.size(); ++i)
    d2.push_back(std::norm(g[i + 1] - 2.0 * g[i] + g[i - 1]));
  std::nth_element(d2.begin(), d2.begin() + long(d2.size() / 2), d2.end());
  return std::sqrt(d2[d2.size() / 2] / (6 * std::numbers::ln2));
}

void CommonPoleOptions::validate() const {
  fit.validate();
  stability.validate();
}

namespace {

// InputError when a curve's valid frequencies wc differ from the first curve's w.
void check_grid(const std::vector<double>& wc, const std::vector<double>& w,
                const std::string& source, const std::string& first) {
  if (wc.size() != w.size()) {
    throw InputError(source + ": " + std::to_string(wc.size()) + " valid points, " + first +
                     " has " + std::to_string(w.size()) + ": common poles need one frequency grid");
  }
  for (size_t i = 0; i < w.size(); ++i) {
    if (std::abs(wc[i] - w[i]) > 1e-9 * w[i]) {
      throw InputError(source + ": point " + std::to_string(i + 1) + " at " +
                       std::to_string(wc[i]) + " rad/s, " + first + "'s at " +
                       std::to_string(w[i]) + ": common poles need one frequency grid");
    }
  }
}

// The relative floor of one curve from a fit's residual (common_poles.h).
double relative_floor(const PoleSetFit& f, size_t c, const std::vector<double>& w,
                      const std::vector<C>& g, const std::vector<double>& W) {
  std::vector<double> r;
  for (size_t i = 0; i < w.size(); ++i) {
    const double noise2 = W[i] > 0 ? 1 / W[i] : 0.0;
    r.push_back(std::max(0.0, std::norm(f.at(c, w[i]) - g[i]) - noise2) /
                std::max(std::norm(g[i]), 1e-300));
  }
  std::nth_element(r.begin(), r.begin() + long(r.size() / 2), r.end());
  return std::sqrt(r[r.size() / 2]);
}

// The curves' valid points on their one grid w, with their weights (1 / sigma^2, or the
// estimated noise's; one level for all when unweighted), into r.curves. InputError naming the
// source of a curve that is too short, off the first curve's grid, or without sigma or noise.
struct CurveData {
  std::vector<double> w;
  std::vector<std::vector<C>> g;
  std::vector<std::vector<double>> W;
};

CurveData read_curves(const std::vector<Frd>& curves, const std::vector<std::string>& sources,
                      bool unweighted, CommonPoleResult& r) {
  CurveData d;
  d.g.resize(curves.size());
  d.W.resize(curves.size());
  for (size_t c = 0; c < curves.size(); ++c) {
    CommonPoleCurve info;
    info.source = sources[c];
    info.pair = curves[c].pair;
    std::vector<double> wc, sigma;
    bool all_sigma = true;
    for (const FrdPoint& p : curves[c].points) {
      if (!p.valid) continue;
      wc.push_back(p.w);
      d.g[c].push_back(p.value());
      sigma.push_back(p.sigma);
      all_sigma = all_sigma && p.sigma > 0;
    }
    if (wc.size() < 4) throw InputError(sources[c] + ": fewer than 4 valid points");
    if (c == 0) d.w = wc;
    check_grid(wc, d.w, sources[c], sources[0]);
    info.sigma_given = all_sigma;
    if (!all_sigma) info.noise = second_difference_noise(d.g[c]);
    for (size_t i = 0; i < d.g[c].size(); ++i) {
      const double s = all_sigma ? sigma[i] : info.noise;
      d.W[c].push_back(s > 0 ? 1 / (s * s) : 0.0);
    }
    if (!all_sigma && !(info.noise > 0)) {
      throw InputError(sources[c] +
                       ": no sigma and no noise seen in its second differences (a curve without "
                       "noise needs sigma, e.g. a column of a small constant)");
    }
    r.curves.push_back(info);
  }
  if (unweighted) {
    double level = 0;
    for (size_t c = 0; c < d.g.size(); ++c) {
      const double n = second_difference_noise(d.g[c]);
      level += n * n / double(d.g.size());
    }
    level = std::sqrt(level);
    if (!(level > 0))
      throw InputError("common poles: no noise seen in any curve's second differences");
    for (size_t c = 0; c < d.g.size(); ++c) {
      d.W[c].assign(d.w.size(), 1 / (level * level));
      r.curves[c].sigma_given = false;
      r.curves[c].noise = level;
    }
  }
  return d;
}

// The pole set fitted again on each curve's relative floor (common_poles.h), when the floor is
// not zero everywhere and the fit does not fail; d.W then holds the weights it used.
void refit_on_relative_floor(CurveData& d, const CommonPoleOptions& o, CommonPoleResult& r) {
  std::vector<std::vector<double>> Wf = d.W;
  bool any = false;
  for (size_t c = 0; c < d.g.size(); ++c) {
    const double rho = relative_floor(r.fit, c, d.w, d.g[c], d.W[c]);
    r.curves[c].rel_floor = rho;
    any = any || rho > 0;
    for (size_t i = 0; i < d.w.size(); ++i) {
      const double noise2 = d.W[c][i] > 0 ? 1 / d.W[c][i] : 0.0;
      const double v = noise2 + rho * rho * std::norm(d.g[c][i]);
      Wf[c][i] = v > 0 ? 1 / v : 0.0;
    }
  }
  if (!any) return;
  const PoleSetFit again = fit_pole_set(d.w, d.g, Wf, o.fit);
  if (again.status == PoleSetFit::Status::kFailed) return;
  r.fit_against_sigma = r.fit.message;
  r.fit = again;
  r.floor_taken = true;
  d.W = Wf;
}

// Each curve's and the total errors of r.fit.
void figures(const CurveData& d, CommonPoleResult& r) {
  double total = 0, log_total = 0;
  const double M = double(d.w.size());
  for (size_t c = 0; c < d.g.size(); ++c) {
    double e = 0, v = 0, l = 0;
    for (size_t i = 0; i < d.w.size(); ++i) {
      const C f = r.fit.at(c, d.w[i]);
      e += std::norm(f - d.g[c][i]);
      v += std::norm(d.g[c][i]);
      // A zero on either side has no finite log ratio; such a point counts as a ratio of e.
      l += std::abs(f) > 0 && std::abs(d.g[c][i]) > 0 ? std::norm(std::log(f / d.g[c][i])) : 1.0;
    }
    r.curves[c].rms_error = std::sqrt(e / M);
    r.curves[c].rms_value = std::sqrt(v / M);
    r.curves[c].rms_log_error = std::sqrt(l / M);
    total += e / M;
    log_total += l;
  }
  r.rms_total = std::sqrt(total);
  r.rms_log_total = std::sqrt(log_total / (M * double(d.g.size())));
}

}  // namespace

CommonPoleResult fit_common_poles(const std::vector<Frd>& curves,
                                  const std::vector<std::string>& sources,
                                  const CommonPoleOptions& o) {
  o.validate();
  if (curves.empty() || curves.size() != sources.size())
    throw InputError("common poles: no curve (or a curve without its source)");
  CommonPoleResult r;
  CurveData d = read_curves(curves, sources, o.unweighted, r);
  r.fit = fit_pole_set(d.w, d.g, d.W, o.fit);
  if (r.fit.status == PoleSetFit::Status::kFailed)
    throw InputError("common poles: " + r.fit.message);
  if (o.relative_floor && !o.unweighted && r.fit.status != PoleSetFit::Status::kAdequate)
    refit_on_relative_floor(d, o, r);
  if (o.stabilisation) {
    StabilisationOptions so = o.stability;
    so.max_pairs = std::max(1, std::min(so.max_pairs, (r.fit.order + 1) / 2));
    r.diagram = stabilisation_diagram(d.w, d.g, d.W, so);
    for (const C& p : r.fit.poles) {
      r.physical.push_back(physical_pole(*r.diagram, p, so));
      r.stable_rows.push_back(stable_rows(*r.diagram, p, so));
    }
  }
  figures(d, r);
  r.w = std::move(d.w);
  r.g = std::move(d.g);
  return r;
}

bool render_common_poles_diagram(const CommonPoleResult& r, const std::string& png) {
  if (!r.diagram) return false;
  std::vector<C> physical;
  for (size_t k = 0; k < r.fit.poles.size(); ++k)
    if (r.physical[k]) physical.push_back(r.fit.poles[k]);
  return render_stabilisation_diagram(*r.diagram, physical, r.w, r.g, png);
}

Json common_poles_to_json(const CommonPoleResult& r) {
  Json j;
  j["format"] = "fralab-common-poles/1";
  const PoleSetFit& f = r.fit;
  j["fit"] = {{"status", f.status == PoleSetFit::Status::kAdequate ? "adequate" : "not_adequate"},
              {"message", f.message},
              {"order", f.order},
              {"chi2_per_dof", f.chi2_per_dof},
              {"rms_error_total", r.rms_total},
              {"rounds", f.rounds},
              {"added", f.added},
              {"skimmed", f.skimmed},
              {"rms_log_error_total", r.rms_log_total},
              {"relative_floor", r.floor_taken}};
  if (r.floor_taken) j["fit"]["fit_against_sigma"] = r.fit_against_sigma;
  j["poles"] = Json::array();
  for (size_t k = 0; k < f.poles.size(); ++k) {
    const C p = f.poles[k];
    Json pj{{"real", p.real()},
            {"imag", p.imag()},
            {"wn", std::abs(p)},
            {"zeta", -p.real() / std::abs(p)},
            {"f_hz", std::abs(p) / (2 * std::numbers::pi)}};
    if (r.diagram) {
      pj["physical"] = bool(r.physical[k]);
      pj["stable_rows"] = r.stable_rows[k];
    }
    j["poles"].push_back(pj);
  }
  j["curves"] = Json::array();
  for (size_t c = 0; c < r.curves.size(); ++c) {
    const CommonPoleCurve& k = r.curves[c];
    Json cj;
    cj["source"] = k.source;
    if (!k.pair.empty()) cj["pair"] = k.pair;
    cj["tf"] = tf_to_json(f.to_tf(c));
    cj["d"] = f.d[c];
    cj["residues"] = Json::array();
    for (const C& x : f.residues[c]) cj["residues"].push_back({x.real(), x.imag()});
    cj["rms_error"] = k.rms_error;
    cj["rms_value"] = k.rms_value;
    cj["rms_log_error"] = k.rms_log_error;
    if (r.floor_taken) cj["relative_floor"] = k.rel_floor;
    cj["chi2"] = f.chi2[c];
    cj["sigma"] = k.sigma_given ? Json("given") : Json(k.noise);
    j["curves"].push_back(cj);
  }
  if (r.diagram) j["stabilisation"] = stabilisation_to_json(*r.diagram);
  return j;
}

}  // namespace fralab
