// What the later stages measure a model by (docs/method/diagnosis.md, "The error metric"): the
// simulation extended by a set of findings, and its error over some pairs on the fitting or the
// validation measurement.
#include <algorithm>
#include <cmath>

#include "fralab/core/numerics.h"
#include "stages.h"

namespace fralab::diag {

double pair_error(const std::vector<double>& w, const std::vector<C>& meas,
                  const std::function<std::optional<C>(double, size_t)>& model) {
  std::vector<C> g;
  for (size_t i = 0; i < w.size(); ++i) g.push_back(model(w[i], i).value_or(0.0));
  return detail::rms_log_error(g, meas);
}

std::vector<const PairFit*> fitted_pairs(const DiagnosisRun& r,
                                         const std::vector<std::string>& which) {
  std::vector<const PairFit*> out;
  for (const std::vector<PairFit>* set : {&r.original, &r.absent})
    for (const PairFit& p : *set)
      if (std::find(which.begin(), which.end(), p.pair) != which.end()) out.push_back(&p);
  return out;
}

size_t points_of(const std::vector<const PairFit*>& pairs) {
  size_t n = 0;
  for (const PairFit* p : pairs) n += p->w.size();
  return n;
}

double bic_penalty(const std::vector<const PairFit*>& pairs) {
  return std::log(2.0 * double(std::max<size_t>(points_of(pairs), 1)));
}

bool quiet_over(const DiagnosisRun& r, const std::vector<Finding>& before,
                const std::vector<Finding>& after, const std::vector<std::string>& which) {
  const Model mb = extended_by(r, before, before.size()), ma = extended_by(r, after, after.size());
  for (const std::string& q : which) {
    const auto qp = fitted_pairs(r, {q});
    if (chi2_of(r, ma, qp) - chi2_of(r, mb, qp) > bic_penalty(qp)) return false;
  }
  return true;
}

double chi2_of(const DiagnosisRun& r, const Model& m, const std::vector<const PairFit*>& pairs) {
  double c = 0;
  for (const PairFit* p : pairs)
    for (size_t q = 0; q < p->w.size(); ++q) {
      const C g =
          model_pair_response(m, p->pair, p->w[q], p->amp[q], r.opt.chain, p->ms).value_or(0.0);
      c += std::norm(p->meas[q] - g) / (p->sig[q] * p->sig[q]);
    }
  return c;
}

Model extended_by(const DiagnosisRun& r, const std::vector<Finding>& fs, size_t skip) {
  Model m = r.sim;
  for (size_t i = 0; i < fs.size(); ++i)
    if (i != skip) cause_unit(fs[i].cause)->apply(m, fs[i]);
  return m;
}

double error_over(const DiagnosisRun& r, const Model& m, const std::vector<std::string>& which,
                  bool validation) {
  double s = 0;
  int n = 0;
  for (const auto& mp : r.data) {
    if (!which.empty() && std::find(which.begin(), which.end(), mp.pair) == which.end()) continue;
    const Frd& f = validation ? mp.validation : mp.frd;
    bool known = false;
    for (const auto& p : r.original) known |= p.pair == mp.pair;
    // A pair the simulation has no path for counts where a finding names it, never in a total
    // (the simulation's error there is unbounded).
    for (const auto& p : r.absent) known |= !which.empty() && p.pair == mp.pair;
    if (!known || f.points.empty()) continue;
    std::vector<double> w;
    std::vector<C> meas;
    std::vector<double> amp;
    std::vector<const MultisineExcitation*> ms;
    for (const auto& pt : f.points) {
      if (!usable(pt, r.opt)) continue;
      w.push_back(pt.w);
      meas.push_back(pt.value());
      amp.push_back(pt.amplitude);
      ms.push_back(multisine_of(r, mp.pair, pt.line_amplitude, validation));
    }
    if (w.empty()) continue;
    // A model with no response on the pair (a path it lacks) errs by 1 there (100 %).
    const bool responds =
        model_pair_response(m, mp.pair, w[0], amp[0], r.opt.chain, ms[0]).has_value();
    double e = !responds ? 1.0 : pair_error(w, meas, [&](double x, size_t i) {
      return model_pair_response(m, mp.pair, x, amp[i], r.opt.chain, ms[i]);
    });
    s += e * e * w.size();
    n += int(w.size());
  }
  return n ? std::sqrt(s / n) : -1.0;
}

}  // namespace fralab::diag

namespace fralab {

double model_error(const Model& m, const Model& sim, const std::vector<MeasuredPair>& data,
                   const DiagnoseOptions& opt, const std::vector<std::string>& which) {
  diag::DiagnosisRun r(sim, data, opt);
  diag::prepare(r);
  return diag::error_over(r, m, which, false);
}

}  // namespace fralab
