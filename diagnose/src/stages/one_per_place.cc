// Stage 5c's last steps (docs/method/diagnosis.md, "The stages"): one finding per place and per
// root. Two delays or two gains at one place are their sum; a move of a root another finding at
// its place added or moved is that finding moved.
#include <algorithm>
#include <cmath>

#include "stages.h"

namespace fralab::diag {
namespace {

// Whether f and g sit at one place: the same scope, input, output and pairs.
bool same_place(const Finding& f, const Finding& g) {
  if (f.scope != g.scope || f.input != g.input || f.output != g.output) return false;
  std::vector<std::string> pf = f.pairs, pg = g.pairs;
  std::sort(pf.begin(), pf.end());
  std::sort(pg.begin(), pg.end());
  return pf == pg;
}

}  // namespace

// Two delays or two gains at one place (scope, input, output, pairs) are one effect, their sum: a
// group's and the composing remainders its rest pairs kept, joined again at the group's scope.
// True when any were joined.
bool one_per_place(std::vector<Finding>& fs) {
  bool joined = false;
  for (size_t a = 0; a < fs.size(); ++a) {
    const CauseKind c = fs[a].cause;
    if (c != CauseKind::kTimeDelay && c != CauseKind::kGainMismatch) continue;
    const Param key = c == CauseKind::kTimeDelay ? Param::kDelayS : Param::kGainDb;
    for (size_t b = a + 1; b < fs.size(); ++b) {
      const Finding& g = fs[b];
      if (g.cause != c || g.scope != fs[a].scope || g.input != fs[a].input ||
          g.output != fs[a].output || !g.by_value())
        continue;
      std::vector<std::string> pa = fs[a].pairs, pb = g.pairs;
      std::sort(pa.begin(), pa.end());
      std::sort(pb.begin(), pb.end());
      if (pa != pb || !fs[a].parameters.count(key) || !g.parameters.count(key)) continue;
      fs[a].parameters[key] += g.parameters.at(key);
      fs.erase(fs.begin() + std::ptrdiff_t(b));
      joined = true;
      --b;
    }
  }
  return joined;
}

// A pole shift or damping error that moves a root another finding at its place added (a missing
// resonance's pair, a missing lag's pole) or moved (a pole shift's to), within kSameRoot, is that
// finding with the root moved: one finding. A resonance moved past critical damping is two real
// poles, wn (zeta -+ sqrt(zeta^2 - 1)); where the faster lies beyond kFarBeyondBand times its
// pairs' highest measured frequency (its phase there under 0.01 rad), it is a lag at the slower.
// True when any was folded.
bool moved_roots_folded(DiagnosisRun& r) {
  constexpr double kSameRoot = 1e-3, kFarBeyondBand = 100;
  std::vector<Finding>& fs = r.findings;
  bool folded = false;
  for (size_t a = 0; a < fs.size(); ++a) {
    const Finding& f = fs[a];
    const std::optional<Param> key = moved_root_key(f.cause);
    if ((f.cause != CauseKind::kPoleShift && f.cause != CauseKind::kDampingError) || !key ||
        !f.parameters.count(*key))
      continue;
    const double from = f.parameters.at(*key);
    for (size_t b = 0; b < fs.size(); ++b) {
      Finding& g = fs[b];
      const bool shift = f.cause == CauseKind::kPoleShift;
      const bool resonance = g.cause == CauseKind::kMissingResonance,
                 lag = g.cause == CauseKind::kMissingLag && shift,
                 moved = g.cause == CauseKind::kPoleShift && shift;
      if (b == a || !g.by_value() || !(resonance || lag || moved) || !same_place(f, g)) continue;
      const Param root_key = resonance ? Param::kWnRadS : lag ? Param::kCornerRadS : Param::kToRadS;
      if (!g.parameters.count(root_key)) continue;
      const double root = g.parameters.at(root_key);
      if (!(std::abs(from - root) <= kSameRoot * root)) continue;
      if (lag) {
        g.parameters[root_key] = f.parameters.at(Param::kToRadS);
      } else if (moved) {  // the root g moved, moved on: g to where f took it
        g.parameters[root_key] = f.parameters.at(Param::kToRadS);
        for (const Param k : {Param::kToZeta, Param::kZeta})
          if (f.parameters.count(k) && g.parameters.count(k)) g.parameters[k] = f.parameters.at(k);
      } else {
        const double wn = f.cause == CauseKind::kPoleShift ? f.parameters.at(Param::kToRadS)
                                                           : g.parameters.at(root_key);
        const double zeta = f.parameters.count(Param::kToZeta) ? f.parameters.at(Param::kToZeta)
                                                               : g.parameters.at(Param::kZeta);
        g.parameters = {{Param::kWnRadS, wn}, {Param::kZeta, zeta}};
        double top = 0;
        for (const PairFit* p : fitted_pairs(r, g.pairs))
          for (double w : p->w) top = std::max(top, w);
        // The two real poles' product is wn^2: the slower from the faster, free of cancellation.
        const double fast = zeta >= 1 ? wn * (zeta + std::sqrt(zeta * zeta - 1)) : 0;
        if (fast > kFarBeyondBand * top) {
          g.cause = CauseKind::kMissingLag;
          g.parameters = {{Param::kCornerRadS, wn * wn / fast}};
        }
      }
      fs.erase(fs.begin() + std::ptrdiff_t(a));
      folded = true;
      a = size_t(-1);  // the list changed: look again from its start
      break;
    }
  }
  return folded;
}

}  // namespace fralab::diag
