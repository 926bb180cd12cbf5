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

CommonPoleResult fit_common_poles(const std::vector<Frd>& curves,
                                  const std::vector<std::string>& sources,
                                  const PoleSetFitOptions& o, bool unweighted) {
  if (curves.empty() || curves.size() != sources.size())
    throw InputError("common poles: no curve (or a curve without its source)");
  std::vector<double> w;
  std::vector<std::vector<C>> g(curves.size());
  std::vector<std::vector<double>> W(curves.size());
  CommonPoleResult r;
  for (size_t c = 0; c < curves.size(); ++c) {
    CommonPoleCurve info;
    info.source = sources[c];
    info.pair = curves[c].pair;
    std::vector<double> wc, sigma;
    bool all_sigma = true;
    for (const FrdPoint& p : curves[c].points) {
      if (!p.valid) continue;
      wc.push_back(p.w);
      g[c].push_back(p.value());
      sigma.push_back(p.sigma);
      all_sigma = all_sigma && p.sigma > 0;
    }
    if (wc.size() < 4) throw InputError(sources[c] + ": fewer than 4 valid points");
    if (c == 0) {
      w = wc;
    } else {
      if (wc.size() != w.size()) {
        throw InputError(sources[c] + ": " + std::to_string(wc.size()) + " valid points, " +
                         sources[0] + " has " + std::to_string(w.size()) +
                         ": common poles need one frequency grid");
      }
      for (size_t i = 0; i < w.size(); ++i) {
        if (std::abs(wc[i] - w[i]) > 1e-9 * w[i]) {
          throw InputError(sources[c] + ": point " + std::to_string(i + 1) + " at " +
                           std::to_string(wc[i]) + " rad/s, " + sources[0] + "'s at " +
                           std::to_string(w[i]) + ": common poles need one frequency grid");
        }
      }
    }
    info.sigma_given = all_sigma;
    if (!all_sigma) info.noise = second_difference_noise(g[c]);
    for (size_t i = 0; i < g[c].size(); ++i) {
      const double s = all_sigma ? sigma[i] : info.noise;
      W[c].push_back(s > 0 ? 1 / (s * s) : 0.0);
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
    for (size_t c = 0; c < g.size(); ++c) {
      const double n = second_difference_noise(g[c]);
      level += n * n / double(g.size());
    }
    level = std::sqrt(level);
    if (!(level > 0))
      throw InputError("common poles: no noise seen in any curve's second differences");
    for (size_t c = 0; c < g.size(); ++c) {
      W[c].assign(w.size(), 1 / (level * level));
      r.curves[c].sigma_given = false;
      r.curves[c].noise = level;
    }
  }
  r.fit = fit_pole_set(w, g, W, o);
  if (r.fit.status == PoleSetFit::Status::kFailed)
    throw InputError("common poles: " + r.fit.message);
  double total = 0;
  for (size_t c = 0; c < curves.size(); ++c) {
    double e = 0, v = 0;
    for (size_t i = 0; i < w.size(); ++i) {
      e += std::norm(r.fit.at(c, w[i]) - g[c][i]);
      v += std::norm(g[c][i]);
    }
    r.curves[c].rms_error = std::sqrt(e / double(w.size()));
    r.curves[c].rms_value = std::sqrt(v / double(w.size()));
    total += e / double(w.size());
  }
  r.rms_total = std::sqrt(total);
  return r;
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
              {"skimmed", f.skimmed}};
  j["poles"] = Json::array();
  for (const C& p : f.poles) {
    j["poles"].push_back({{"real", p.real()},
                          {"imag", p.imag()},
                          {"wn", std::abs(p)},
                          {"zeta", -p.real() / std::abs(p)},
                          {"f_hz", std::abs(p) / (2 * std::numbers::pi)}});
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
    cj["chi2"] = f.chi2[c];
    cj["sigma"] = k.sigma_given ? Json("given") : Json(k.noise);
    j["curves"].push_back(cj);
  }
  return j;
}

}  // namespace fralab
