#include "corner.h"

#include <cmath>

namespace fralab::diag {

Cause fit_corner(CauseKind kind, bool lead, const PairFit& p, const DiagnoseOptions& opt) {
  constexpr int kGrid = 80;
  const double widen = std::pow(10.0, opt.corner_decades_beyond);
  auto F = [&](double la) {
    const double a = std::exp(la);
    return factor_of(p.w, [&](C s) { return lead ? 1.0 + s / a : 1.0 / (1.0 + s / a); });
  };
  const double la = minimise_1d([&](double x) { return chi2(p, F(x)); },
                                std::log(p.w.front() / widen), std::log(p.w.back() * widen), kGrid);
  Cause c{kind, {{Param::kCornerRadS, std::exp(la)}}, F(la), 0, 1, ""};
  c.chi2 = chi2(p, c.F);
  return c;
}

}  // namespace fralab::diag
