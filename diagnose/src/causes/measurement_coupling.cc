#include "measurement_coupling.h"

#include <cmath>

#include "cause.h"

namespace fralab::diag {

std::optional<Finding> fit_measurement_coupling(const Model& sim, const ModelInput& in,
                                                std::vector<PairFit>& pairs,
                                                const DiagnoseOptions& opt) {
  std::vector<size_t> idx;
  int act = -1;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (pairs[k].input != in.name) continue;
    idx.push_back(k);
    if (pairs[k].output.empty()) act = int(k);
  }
  if (act < 0 || idx.size() < 2) return std::nullopt;
  const int i = sim.input_index(in.name);
  double base = 0;
  for (size_t k : idx) base += chi2(pairs[k], std::vector<C>(pairs[k].w.size(), 1.0));
  std::string best_o;
  double best_g = 0, best_c = base;
  for (const auto& out : sim.outputs) {
    const int o = sim.output_index(out.name);
    if (!sim.path(out.name, in.name)) continue;
    double hmax = 0;
    for (double w : pairs[act].w) hmax = std::max(hmax, std::abs(sim.position_to_output(o, i, w)));
    if (hmax == 0) continue;
    auto F = [&](const PairFit& p, double g) {
      return factor_of(p.w, [&](C s) {
        C h = 1.0 + g * sim.position_to_output(o, i, s.imag());
        return p.output.empty() ? h : 1.0 / h;
      });
    };
    auto total = [&](double g) {
      double c = 0;
      for (size_t k : idx) c += chi2(pairs[k], F(pairs[k], g));
      return c;
    };
    double g = minimise_1d(total, -0.9 / hmax, 0.9 / hmax, 200);
    double c = total(g);
    if (c < best_c) best_c = c, best_g = g, best_o = out.name;
  }
  double n = 0;
  for (size_t k : idx) n += pairs[k].w.size();
  // The signature must be in the channel's own actuator response (1 + g H): that pair has to be
  // beyond its uncertainty and be explained by the coupling (a path gain error is not a coupling).
  bool act_signature = false;
  if (!best_o.empty()) {
    const PairFit& a = pairs[act];
    const double na = double(a.w.size());
    const double ca0 = chi2(a, std::vector<C>(a.w.size(), 1.0));
    const int o = sim.output_index(best_o);
    const double ca1 = chi2(a, factor_of(a.w, [&](C s) {
                              return 1.0 + best_g * sim.position_to_output(o, i, s.imag());
                            }));
    act_signature = ca0 > na + 4 * std::sqrt(na) && ca0 - ca1 > opt.min_improvement * ca0;
  }
  if (!(act_signature && base - best_c > std::max(std::log(2 * n), opt.min_improvement * base) &&
        base > n + 4 * std::sqrt(n)))
    return std::nullopt;
  const int o = sim.output_index(best_o);
  Finding f;
  f.cause = CauseKind::kMeasurementCoupling;
  f.scope = Scope::kInput;
  f.input = in.name;
  f.text_parameters = {{"channel", in.name}, {"coupled_to", best_o}};
  f.parameters = {{Param::kGain, best_g}};
  f.explanation = "the " + in.name + " channel records " + in.name + " + " + fmt(best_g) + " * " +
                  best_o + ": its actuator response carries the " + best_o +
                  " response (1 + g H) and every " + in.name + " path divides by it; chi2 " +
                  fmt(base) + " -> " + fmt(best_c) + " over " + std::to_string(idx.size()) +
                  " pairs";
  for (size_t k : idx) {
    f.pairs.push_back(pairs[k].pair);
    for (size_t q = 0; q < pairs[k].w.size(); ++q) {
      C h = 1.0 + best_g * sim.position_to_output(o, i, pairs[k].w[q]);
      pairs[k].factor[q] *= pairs[k].output.empty() ? h : 1.0 / h;
    }
  }
  return f;
}

namespace {

// The coupling as a cause: the finding's position channel records its coupled output times the
// gain, which is 0 in the simulation (the primary parameter). The explanation is written when
// fitted.
class MeasurementCoupling final : public CauseUnit {
 public:
  CauseKind kind() const override { return CauseKind::kMeasurementCoupling; }
  const char* name() const override { return "measurement_coupling"; }
  PrimaryParameter primary_parameter(const Finding&) const override { return {Param::kGain, 0.0}; }
  void apply(Model& m, const Finding& f) const override {
    m.inputs[m.input_index(f.input)].measurement_coupling.push_back(
        {f.text_parameters.at("coupled_to"), f.parameters.at(Param::kGain)});
  }
  std::string explain(const Finding& f) const override { return f.explanation; }
};

}  // namespace

const CauseUnit& measurement_coupling_cause() {
  static const MeasurementCoupling c;
  return c;
}

}  // namespace fralab::diag
