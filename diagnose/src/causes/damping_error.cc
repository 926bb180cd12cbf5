// damping_error: a pole pair of the simulated chain at the right frequency with the wrong damping,
// F = D_sim(s) / D(s; wn, to_zeta) with D = s^2/wn^2 + 2 zeta s/wn + 1; parameters wn_rad_s,
// from_zeta, to_zeta. Search: ln zeta over [ln 0.002, ln 2] (grid then Brent's method), one
// candidate per simulated pair. Consistent across pairs: wn and to_zeta within
// DiagnoseOptions::consistent_rel. Extension: the pair at wn takes to_zeta.
#include <cmath>

#include "cause.h"
#include "fralab/core/error.h"
#include "mode_residues.h"

namespace fralab::diag {
namespace {

std::vector<Root> chain_pairs(const Model& m, const PairFit& p) {
  std::vector<Root> v;
  auto add = [&](const Tf& t) {
    for (const Root& r : t.poles)
      if (r.pair) v.push_back(r);
  };
  const int i = m.input_index(p.input);
  if (p.output.empty()) {
    if (m.inputs[i].actuator) add(*m.inputs[i].actuator);
    return v;
  }
  if (const ModelPath* mp = m.path(p.output, p.input)) add(mp->tf);
  const int o = m.output_index(p.output);
  if (m.outputs[o].sensor) add(*m.outputs[o].sensor);
  return v;
}

// A transfer function holds the pair when one of its pairs is this close (relative): the mean of
// several paths' wn_rad_s carries rounding only.
constexpr double kSamePair = 1e-3;

class DampingError final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kDampingError; }
  const char* name() const override { return "damping_error"; }
  // to_zeta, in the simulation the pole pair's own damping from_zeta.
  PrimaryParameter primary_parameter(const Finding& f) const override {
    return {Param::kToZeta, f.parameters.at(Param::kFromZeta)};
  }
  void fit(const Model& m, const PairFit& p, const DiagnoseOptions&,
           std::vector<Cause>* out) const override {
    constexpr int kGrid = 80;
    for (const Root& r : chain_pairs(m, p)) {
      auto F = [&](double lz) {
        Root q = r;
        q.zeta = std::exp(lz);
        return factor_of(p.w, [&](C s) { return r.factor(s) / q.factor(s); });
      };
      const double lz =
          minimise_1d([&](double x) { return chi2(p, F(x)); }, std::log(kDampingSearchMin),
                      std::log(kDampingSearchMax), kGrid);
      Cause c{kind(),
              {{Param::kWnRadS, r.wn}, {Param::kFromZeta, r.zeta}, {Param::kToZeta, std::exp(lz)}},
              F(lz),
              0,
              1,
              ""};
      c.chi2 = chi2(p, c.F);
      out->push_back(std::move(c));
    }
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    return params_within(a, b, {Param::kWnRadS, Param::kToZeta}, opt.consistent_rel);
  }
  bool acts_on(const Tf& t, const Finding& f) const override {
    const double wn = f.parameters.at(Param::kWnRadS);
    for (const Root& r : t.poles)
      if (r.pair && std::abs(r.wn - wn) <= kSamePair * wn) return true;
    return false;
  }
  // The held pair takes to_zeta; a transfer function without it takes the factor D_sim / D as a
  // zero pair and a pole pair.
  void extend(Tf& t, const Finding& f) const override {
    const double wn = f.parameters.at(Param::kWnRadS), to_zeta = f.parameters.at(Param::kToZeta);
    const bool shape_kept =
        f.text_parameters.count("form") && f.text_parameters.at("form") == "residue";
    for (Root& r : t.poles)
      if (r.pair && std::abs(r.wn - wn) <= kSamePair * wn) {
        // A structure's mode re-damped with its shape kept (modes stage): the zeros move too.
        if (shape_kept)
          if (auto moved = moved_keeping_residue(t, r, Root::Pair(r.wn, to_zeta))) {
            t = *moved;
            return;
          }
        r.zeta = to_zeta;
        return;
      }
    const auto from_zeta = f.parameters.find(Param::kFromZeta);
    if (from_zeta == f.parameters.end())
      throw InputError("damping_error at " + fmt(wn) +
                       " rad/s: no pole pair there, and no from_zeta to add its factor with");
    t.zeros.push_back(Root::Pair(wn, from_zeta->second));
    t.poles.push_back(Root::Pair(wn, to_zeta));
  }
  std::string explain(const Finding& f) const override {
    return "the simulated pair at " + fmt(f.parameters.at(Param::kWnRadS)) + " rad/s is damped " +
           fmt(f.parameters.at(Param::kToZeta)) + " in the data, not " +
           fmt(f.parameters.at(Param::kFromZeta));
  }
};

}  // namespace

const LinearCause& damping_error_cause() {
  static const DampingError c;
  return c;
}

}  // namespace fralab::diag
