// pole_shift: F = D_from(s) / D_to(s): one real pole or pair of the simulated chain (actuator for
// u_X:X; path and sensor for X:O) moved from `from` to `to` (pairs keep their damping, reported as
// zeta), from_rad_s and to_rad_s. Search: ln to over [from / r, from * r] with
// r = DiagnoseOptions::pole_shift_range, grid then Brent's method; one candidate per simulated
// pole. Consistent across pairs: from and to within DiagnoseOptions::consistent_rel.
#include <cmath>

#include "cause.h"

namespace fralab::diag {
namespace {

// The simulated chain's poles for a pair.
std::vector<Root> chain_poles(const Model& m, const PairFit& p) {
  std::vector<Root> v;
  const int i = m.input_index(p.input);
  if (p.output.empty()) {
    if (m.inputs[i].actuator) v = m.inputs[i].actuator->poles;
    return v;
  }
  if (const ModelPath* mp = m.path(p.output, p.input)) v = mp->tf.poles;
  const int o = m.output_index(p.output);
  if (m.outputs[o].sensor)
    v.insert(v.end(), m.outputs[o].sensor->poles.begin(), m.outputs[o].sensor->poles.end());
  return v;
}

class PoleShift final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kPoleShift; }
  const char* name() const override { return "pole_shift"; }
  // to_rad_s, in the simulation the pole's own frequency from_rad_s; a frequency stays positive.
  PrimaryParameter primary_parameter(const Finding& f) const override {
    return {"to_rad_s", f.parameters.at("from_rad_s")};
  }
  IntervalDomain interval_domain() const override { return {true, 1e-6}; }
  void fit(const Model& m, const PairFit& p, const DiagnoseOptions& opt,
           std::vector<Cause>* out) const override {
    constexpr int kGrid = 120;
    for (const Root& r : chain_poles(m, p)) {
      const double from = r.pair ? r.wn : -r.real;
      auto F = [&](double lto) {
        const double to = std::exp(lto);
        Root q = r;
        if (q.pair)
          q.wn = to;
        else
          q.real = -to;
        return factor_of(p.w, [&](C s) { return r.factor(s) / q.factor(s); });
      };
      const double lto = minimise_1d([&](double x) { return chi2(p, F(x)); },
                                     std::log(from / opt.pole_shift_range),
                                     std::log(from * opt.pole_shift_range), kGrid);
      Cause c{kind(), {{"from_rad_s", from}, {"to_rad_s", std::exp(lto)}}, F(lto), 0, 1, ""};
      if (r.pair) c.params["zeta"] = r.zeta;
      c.chi2 = chi2(p, c.F);
      out->push_back(std::move(c));
    }
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    return params_within(a, b, {"from_rad_s", "to_rad_s"}, opt.consistent_rel);
  }
  void extend(Tf& t, const Finding& f) const override {
    const double from = f.parameters.at("from_rad_s"), to = f.parameters.at("to_rad_s");
    Root* best = nullptr;
    for (Root& r : t.poles) {
      const double v = r.pair ? r.wn : -r.real;
      if (!best || std::abs(v - from) < std::abs((best->pair ? best->wn : -best->real) - from))
        best = &r;
    }
    if (!best) return;
    if (best->pair)
      best->wn = to;
    else
      best->real = -to;
  }
  std::string explain(const Finding& f) const override {
    return "the simulated pole at " + fmt(f.parameters.at("from_rad_s")) + " rad/s sits at " +
           fmt(f.parameters.at("to_rad_s")) + " rad/s in the data";
  }
};

}  // namespace

const LinearCause& pole_shift_cause() {
  static const PoleShift c;
  return c;
}

}  // namespace fralab::diag
