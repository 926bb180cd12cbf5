// pole_shift: F = D_from(s) / D_to(s): one real pole or pair of the simulated chain (actuator for
// u_X:X; path and sensor for X:O) moved from `from` to `to`, from_rad_s and to_rad_s. Search: ln to
// over [from / r, from * r] with r = DiagnoseOptions::pole_shift_range, grid then Brent's method;
// one candidate per simulated pole. A pair moves as a whole: its damping is then fitted with its
// frequency (alternate Brent searches from the frequency found at the simulated damping, ln zeta
// over [ln 0.002, ln 2]), and kept when the second parameter lowers chi2 by more than its BIC
// penalty ln 2N; otherwise the pair keeps the simulated damping. Reported as from_zeta (the
// simulation's), to_zeta (the data's; equal to from_zeta when kept) and zeta (= to_zeta, the moved
// pair's damping). Consistent across pairs: from and to within DiagnoseOptions::consistent_rel.
#include <cmath>

#include "cause.h"
#include "fralab/core/numerics.h"
#include "mode_residues.h"

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

constexpr int kDampingRounds = 8;  // frequency / damping alternations at most
// A transfer function holds the moved root when one of its roots is this close (relative): the
// mean of several paths' from_rad_s carries rounding only.
constexpr double kSameRoot = 1e-3;

// A pair's damping was fitted (the data resolve it) when it differs from the simulation's; beyond
// rounding, as the mean of several paths' equal values may carry.
bool damping_fitted(const Finding& f) {
  const auto from = f.parameters.find(Param::kFromZeta), to = f.parameters.find(Param::kToZeta);
  return from != f.parameters.end() && to != f.parameters.end() &&
         std::abs(from->second - to->second) > 1e-9 * from->second;
}

class PoleShift final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kPoleShift; }
  const char* name() const override { return "pole_shift"; }
  // to_rad_s, in the simulation the pole's own frequency from_rad_s; a frequency stays positive.
  PrimaryParameter primary_parameter(const Finding& f) const override {
    return {Param::kToRadS, f.parameters.at(Param::kFromRadS)};
  }
  IntervalDomain interval_domain() const override { return {true, 1e-6}; }
  // A pair's damping: its interval is reported either way; it is free only when fitted.
  std::vector<SecondaryParameter> secondary_parameters(const Finding& f) const override {
    if (!f.parameters.count(Param::kToZeta)) return {};
    return {{Param::kToZeta, damping_fitted(f)}};
  }
  void settle(Finding& f) const override {
    if (const auto z = f.parameters.find(Param::kToZeta); z != f.parameters.end())
      f.parameters[Param::kZeta] = z->second;
  }
  void fit(const Model& m, const PairFit& p, const DiagnoseOptions& opt,
           std::vector<Cause>* out) const override {
    constexpr int kGrid = 120;
    for (const Root& r : chain_poles(m, p)) {
      const double from = r.pair ? r.wn : -r.real;
      auto F = [&](double lto, double zeta) {
        const double to = std::exp(lto);
        Root q = r;
        if (q.pair) {
          q.wn = to;
          q.zeta = zeta;
        } else {
          q.real = -to;
        }
        return factor_of(p.w, [&](C s) { return r.factor(s) / q.factor(s); });
      };
      const double lto = minimise_1d([&](double x) { return chi2(p, F(x, r.zeta)); },
                                     std::log(from / opt.pole_shift_range),
                                     std::log(from * opt.pole_shift_range), kGrid);
      Cause c{
          kind(), {{Param::kFromRadS, from}, {Param::kToRadS, std::exp(lto)}}, F(lto, r.zeta), 0, 1,
          ""};
      c.chi2 = chi2(p, c.F);
      if (r.pair) {
        c.params[Param::kZeta] = c.params[Param::kFromZeta] = c.params[Param::kToZeta] = r.zeta;
        // The pair as a whole: its damping over the whole range at the frequency found, then the
        // two alternately, each near its last value, until both settle.
        double l2 = lto, lz = std::log(r.zeta);
        lz = minimise_1d([&](double x) { return chi2(p, F(l2, std::exp(x))); },
                         std::log(kDampingSearchMin), std::log(kDampingSearchMax), 40);
        for (int round = 0; round < kDampingRounds; ++round) {
          const double l2_was = l2, lz_was = lz;
          l2 = detail::brent_minimum([&](double x) { return chi2(p, F(x, std::exp(lz))); },
                                     l2 - 0.1, l2 + 0.1, 24);
          lz = detail::brent_minimum([&](double x) { return chi2(p, F(l2, std::exp(x))); },
                                     std::max(std::log(kDampingSearchMin), lz - 0.5),
                                     std::min(std::log(kDampingSearchMax), lz + 0.5), 24);
          if (std::abs(l2 - l2_was) < 1e-5 && std::abs(lz - lz_was) < 1e-4) break;
        }
        const std::vector<C> F2 = F(l2, std::exp(lz));
        const double c2 = chi2(p, F2);
        if (c.chi2 - c2 > std::log(2.0 * double(p.w.size()))) {
          c.params[Param::kToRadS] = std::exp(l2);
          c.params[Param::kZeta] = c.params[Param::kToZeta] = std::exp(lz);
          c.F = F2;
          c.chi2 = c2;
          c.k = 2;
        }
      }
      out->push_back(std::move(c));
    }
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    return params_within(a, b, {Param::kFromRadS, Param::kToRadS}, opt.consistent_rel);
  }
  bool acts_on(const Tf& t, const Finding& f) const override {
    const double from = f.parameters.at(Param::kFromRadS);
    for (const Root& r : t.poles)
      if (std::abs((r.pair ? r.wn : -r.real) - from) <= kSameRoot * from) return true;
    return false;
  }
  // The held root moves (a pair takes to_zeta when fitted); a transfer function without it takes
  // the factor itself, D_from / D_to, as a zero at the old root and a pole at the new.
  void extend(Tf& t, const Finding& f) const override {
    const double from = f.parameters.at(Param::kFromRadS), to = f.parameters.at(Param::kToRadS);
    const auto from_zeta = f.parameters.find(Param::kFromZeta),
               to_zeta = f.parameters.find(Param::kToZeta);
    const bool pair = from_zeta != f.parameters.end();  // a pair when the finding says so
    // A structure's mode moved with its residue kept (modes stage): the path's zeros move too.
    if (pair && to_zeta != f.parameters.end() && f.text_parameters.count("form") &&
        f.text_parameters.at("form") == "residue") {
      for (const Root& r : t.poles) {
        if (!r.pair || std::abs(r.wn - from) > kSameRoot * from) continue;
        if (auto moved = moved_keeping_residue(t, r, Root::Pair(to, to_zeta->second))) {
          t = *moved;
          return;
        }
      }
    }
    for (Root& r : t.poles) {
      if (std::abs((r.pair ? r.wn : -r.real) - from) > kSameRoot * from) continue;
      if (r.pair) {
        r.wn = to;
        if (to_zeta != f.parameters.end()) r.zeta = to_zeta->second;
      } else {
        r.real = -to;
      }
      return;
    }
    if (pair) {
      t.zeros.push_back(Root::Pair(from, from_zeta->second));
      t.poles.push_back(
          Root::Pair(to, to_zeta != f.parameters.end() ? to_zeta->second : from_zeta->second));
    } else {
      t.zeros.push_back(Root::Real(-from));
      t.poles.push_back(Root::Real(-to));
    }
  }
  std::string explain(const Finding& f) const override {
    std::string ex = "the simulated pole at " + fmt(f.parameters.at(Param::kFromRadS)) +
                     " rad/s sits at " + fmt(f.parameters.at(Param::kToRadS)) +
                     " rad/s in the data";
    if (!f.parameters.count(Param::kToZeta)) return ex;
    const double from_zeta = f.parameters.at(Param::kFromZeta),
                 to_zeta = f.parameters.at(Param::kToZeta);
    std::string band;
    if (const auto it = f.intervals.find(Param::kToZeta); it != f.intervals.end())
      band = " (1-sigma " + (std::isfinite(it->second[0]) ? fmt(it->second[0]) : "-") + " to " +
             (std::isfinite(it->second[1]) ? fmt(it->second[1]) : "-") + ")";
    if (damping_fitted(f))
      return ex + ", damped " + fmt(to_zeta) + band + ", not " + fmt(from_zeta);
    return ex + "; the simulated damping " + fmt(from_zeta) +
           " is kept: the data do not resolve another" + band;
  }
};

}  // namespace

const LinearCause& pole_shift_cause() {
  static const PoleShift c;
  return c;
}

}  // namespace fralab::diag
