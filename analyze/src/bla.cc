#include "fralab/analyze/bla.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <numbers>
#include <string>
#include <utility>

namespace fralab {

std::vector<FrdPoint> best_linear_approximation(const std::vector<FrdPoint>& points) {
  // Groups in the order of their first point (equal w then keep the analyser's order), and every
  // point not combined in its place.
  std::map<std::pair<std::string, double>, size_t> group_of;
  std::vector<std::vector<const FrdPoint*>> groups;
  std::vector<std::pair<const FrdPoint*, size_t>> order;  // a point, or a group (nullptr, index)
  for (const FrdPoint& p : points) {
    if (!(p.valid && p.sigma > 0)) {
      order.push_back({&p, 0});
      continue;
    }
    auto [it, fresh] = group_of.emplace(std::make_pair(p.input, p.w), groups.size());
    if (fresh) {
      groups.emplace_back();
      order.push_back({nullptr, it->second});
    }
    groups[it->second].push_back(&p);
  }
  std::vector<FrdPoint> out;
  for (const auto& [single, index] : order) {
    if (single) {
      out.push_back(*single);
      continue;
    }
    const std::vector<const FrdPoint*>& g = groups[index];
    if (g.size() < 2) {
      out.push_back(*g.front());
      continue;
    }
    const double R = double(g.size());
    std::complex<double> mean = 0;
    double var_noise = 0, coherence = 0, nl = 0;
    bool has_coherence = true, has_nl = true;
    for (const FrdPoint* p : g) {
      mean += p->value() / R;
      var_noise += p->sigma * p->sigma / (R * R);
      has_coherence &= p->coherence >= 0;
      has_nl &= p->nl_rel >= 0;
      coherence += p->coherence / R;
      nl += p->nl_rel / R;
    }
    double var_total = 0;
    for (const FrdPoint* p : g) var_total += std::norm(p->value() - mean) / (R * (R - 1));
    FrdPoint b = *g.front();
    b.mag = std::abs(mean);
    b.phase_deg = std::arg(mean) * 180 / std::numbers::pi;
    b.sigma = std::sqrt(std::max(var_total, var_noise));
    b.sigma_noise = std::sqrt(var_noise);
    b.sigma_nl = std::sqrt(std::max(0.0, var_total - var_noise));
    b.realisations = int(g.size());
    b.coherence = has_coherence ? coherence : -1.0;
    b.nl_rel = has_nl ? nl : -1.0;
    out.push_back(b);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const FrdPoint& x, const FrdPoint& y) { return x.w < y.w; });
  return out;
}

}  // namespace fralab
