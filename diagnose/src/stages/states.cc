// Stage 3a, states (docs/method/diagnosis.md, "The stages", 3a): where the simulation is a state
// model (plant/state_space.h), its own entries are candidate causes, each fitted over every pair:
// a parameter its owner named (the entries of A, B, C and D it sets, moved together), a diagonal
// entry of A (a state's time constant), a nonzero entry of A off the diagonal (a coupling), of B
// (how an input drives a state) and of C (how a state shows at an output), a state the simulation
// lacks, a first-order lag before an input or after an output (its time constant over the band;
// found as a missing_lag naming the state it adds), and a delay it lacks at an input or an output
// (found as a time_delay there). One changed state moves the poles, zeros and gains of every path
// it reaches; fitted pair by pair it splits into pieces or is missed, or is hidden by another
// change it overlaps.
//
// On each pair the factor G_moved(jw) / G_sim(jw) of its path, both evaluated (state_eval.h) as
// C (jwI - A)^-1 B + D times e^{-jw tau} for the input's and output's delays added to the
// simulation's (the simulation's own delays cancel in the ratio; the actuator's own pair and a
// path the simulation lacks: 1). Several entries changed at once are searched as sets, a beam of
// kBeam sets per size: each set of k entries is extended by every other entry fitted alone on top
// of it (a scan of kScan points, a diagonal entry of A over its logarithm within a factor kSpan
// either way keeping its sign, another entry over +-kSpan times its value, then Brent's method
// between the scan's neighbours), the kScreened best of those are fitted jointly with the set's
// entries (Levenberg-Marquardt, Eigen's), and the kBeam best sets of k + 1 go on; the best of
// them is then improved by swaps (each entry taken out and the best-screened others fitted in its
// place, while chi2 falls). Fitted one at a time, a first entry that stands in for two changed
// ones would stay; fitted as sets, the entries that changed fit together, and a swap takes out a
// first entry that steered the search wrong once those it stood in for are in the set. The best set
// of each size is taken while the next size lowers chi2 by more than ln 2N in units of the misfit
// level s = max(1, chi2 / N) (the modes stage's criterion) and lowers the error of the pairs (the
// search ends at the first size that does not). The accepted entries' factor stays on the pairs, so
// the stages after it fit what they leave; the other sets of as many entries the criterion cannot
// tell from them are given beside (Diagnosis::state_alternatives).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>
#include <unsupported/Eigen/LevenbergMarquardt>
#include <unsupported/Eigen/NumericalDiff>

#include "../causes/state_parameter.h"
#include "fralab/core/numerics.h"
#include "fralab/core/pair_id.h"
#include "state_eval.h"

namespace fralab::diag {
namespace {

constexpr int kScan = 21;
constexpr double kSpan = 4;
constexpr int kMaxEntries = 6;  // entries, lags, delays and parameters in one set
// An added delay's search range: its phase at the band's top, rad (beyond pi the logarithm's
// phase wraps; a delay that large is a path stage's to find).
constexpr std::pair<double, double> kDelayPhase{0.003, 3.0};
constexpr int kStateBrentBits = 24;
constexpr size_t kBeam = 4;
constexpr size_t kScreened = 6;
constexpr int kSwapRounds = 3;
// The step of the linear screen's derivatives, in an entry's coordinate (ln |v| or v / |v0|).
constexpr double kLinearStep = 0.05;
// A residual standing for an unstable state model (Levenberg-Marquardt then refuses the step).
constexpr double kUnstableResidual = 1e8;

// rms |ln(model / measured)| over every prepared pair with F on top of their factors.
double state_error_with(const DiagnosisRun& r, const std::vector<std::vector<C>>& F) {
  double s = 0;
  size_t n = 0;
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    const PairFit& p = r.pairs[k];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C f = F.empty() ? p.factor[q] : p.factor[q] * F[k][q];
      const C m = p.sim[q] * f;
      if (std::abs(m) == 0 || std::abs(p.meas[q]) == 0) continue;
      s += std::norm(std::log(m / p.meas[q]));
      ++n;
    }
  }
  return n ? std::sqrt(s / double(n)) : 0;
}

bool is_rate(const StateEntry& e) {
  return e.added() || e.named() || (e.matrix == 'A' && e.row == e.col);
}

// An entry's coordinate for the fits: ln |v| for a rate (its sign kept), v / |v0| otherwise.
double to_x(const StateEntry& e, double v0, double v) {
  return is_rate(e) ? std::log(std::abs(v)) : v / std::abs(v0);
}
double to_v(const StateEntry& e, double v0, double x) {
  return is_rate(e) ? std::copysign(std::exp(x), v0) : x * std::abs(v0);
}

bool same_entry(const StateEntry& a, const StateEntry& b) {
  return a.matrix == b.matrix && a.row == b.row && a.col == b.col;
}

// Entries of the state model moved together, and chi2 with them moved.
struct EntrySet {
  std::vector<StateEntry> e;
  std::vector<double> v;
  double chi2 = INFINITY;

  // Whether x sets an entry one of the set's sets (or is one of them).
  bool overlaps(const StateSpace& sim, const StateEntry& x) const {
    return std::any_of(e.begin(), e.end(), [&](const StateEntry& y) { return overlap(sim, x, y); });
  }
  // The entries of A, B and C first, then the added lags and delays (with_entry).
  StateSpace applied_to(const StateSpace& sim) const {
    StateSpace ss = sim;
    for (bool added : {false, true})
      for (size_t k = 0; k < e.size(); ++k)
        if (e[k].added() == added) ss = with_entry(ss, e[k], v[k]);
    return ss;
  }
  // The same entries whatever their order.
  std::vector<std::tuple<char, int, int>> key() const {
    std::vector<std::tuple<char, int, int>> out;
    for (const StateEntry& x : e) out.emplace_back(x.matrix, x.row, x.col);
    std::sort(out.begin(), out.end());
    return out;
  }
};

// The state model's named parameters, its nonzero entries of A, B and C (but an entry a
// parameter sets alone, which is that parameter), and the lags and delays it may lack.
std::vector<StateEntry> candidates_of(const StateSpace& ss) {
  std::vector<StateEntry> out;
  for (size_t k = 0; k < ss.parameters.size(); ++k) out.push_back({'P', int(k), 0});
  auto entry = [&](char m, int i, int j) {
    for (const NamedParameter& np : ss.parameters)
      if (np.entries.size() == 1 && np.entries[0].matrix == m && np.entries[0].row == i &&
          np.entries[0].col == j)
        return;
    out.push_back({m, i, j});
  };
  for (int i = 0; i < ss.A.rows(); ++i)
    for (int j = 0; j < ss.A.cols(); ++j)
      if (ss.A(i, j) != 0) entry('A', i, j);
  for (int i = 0; i < ss.B.rows(); ++i)
    for (int j = 0; j < ss.B.cols(); ++j)
      if (ss.B(i, j) != 0) entry('B', i, j);
  for (int i = 0; i < ss.C.rows(); ++i)
    for (int j = 0; j < ss.C.cols(); ++j)
      if (ss.C(i, j) != 0) entry('C', i, j);
  for (int j = 0; j < ss.B.cols(); ++j) out.push_back({'U', 0, j});
  for (int i = 0; i < ss.C.rows(); ++i) out.push_back({'Y', i, 0});
  for (int j = 0; j < ss.B.cols(); ++j) out.push_back({'I', 0, j});
  for (int i = 0; i < ss.C.rows(); ++i) out.push_back({'O', i, 0});
  return out;
}

// Entry e's value and chi2 at the least of chi2_at over its range: around the simulated value v0,
// a rate within a factor kSpan, another entry within kSpan |v0|; a scan of kScan points, then
// Brent's method between the best one's neighbours.
template <class Chi2>
std::pair<double, double> scan_entry(const StateEval& ev, const StateEntry& e, double v0,
                                     const Chi2& chi2_at) {
  const double x0 = e.added() ? 0 : to_x(e, v0, v0), span = is_rate(e) ? std::log(kSpan) : kSpan;
  // An added lag: its time constant from a third of the band's top's to three of its bottom's;
  // an added delay: its phase at the band's top from kDelayPhase.first to .second rad.
  const auto [w_lo, w_hi] = ev.band();
  const double lo = e.lag()     ? std::log(1 / (3 * w_hi))
                    : e.delay() ? std::log(kDelayPhase.first / w_hi)
                                : x0 - span,
               hi = e.lag()     ? std::log(3 / w_lo)
                    : e.delay() ? std::log(kDelayPhase.second / w_hi)
                                : x0 + span;
  std::vector<double> xs(kScan), cs(kScan);
  size_t best = 0;
  for (int q = 0; q < kScan; ++q) {
    xs[size_t(q)] = lo + (hi - lo) * q / (kScan - 1);
    cs[size_t(q)] = chi2_at(xs[size_t(q)]);
    if (cs[size_t(q)] < cs[best]) best = size_t(q);
  }
  if (!std::isfinite(cs[best])) return {v0, INFINITY};
  const double a = xs[best > 0 ? best - 1 : 0], b = xs[std::min(best + 1, xs.size() - 1)];
  const double x = detail::brent_minimum(chi2_at, a, b, kStateBrentBits);
  const double c = chi2_at(x);
  return c < cs[best] ? std::make_pair(to_v(e, v0, x), c)
                      : std::make_pair(to_v(e, v0, xs[best]), cs[best]);
}

// Entry e (not in s) fitted alone on top of the set s (its entries at their values; base = s
// applied to the simulation): its value and chi2. Each point by moved_responses; where the value
// found leaves A unstable, the scan again with the unstable points refused.
std::pair<double, double> fit_alone(const StateEval& ev, const StateSpace& sim, const EntrySet& s,
                                    const StateSpace& base, const StateEntry& e) {
  const double v0 = entry_value(sim, e);
  std::vector<StateEntry> es = s.e;
  std::vector<double> vs = s.v;
  es.push_back(e), vs.push_back(v0);
  Eigen::VectorXd res;
  const auto fast = scan_entry(ev, e, v0, [&](double x) {
    vs.back() = to_v(e, v0, x);
    ev.residuals_moved(es, vs, &res);
    const double c = res.squaredNorm();
    return std::isfinite(c) ? c : INFINITY;
  });
  if (!std::isfinite(fast.second) || StateEval::stable(with_entry(base, e, fast.first)))
    return fast;
  return scan_entry(ev, e, v0, [&](double x) {
    vs.back() = to_v(e, v0, x);
    if (!StateEval::stable(with_entry(base, e, vs.back()))) return double(INFINITY);
    ev.residuals_moved(es, vs, &res);
    const double c = res.squaredNorm();
    return std::isfinite(c) ? c : INFINITY;
  });
}

// The residuals of a set of entries at coordinates x, for Eigen's Levenberg-Marquardt.
struct SetResiduals : Eigen::DenseFunctor<double> {
  SetResiduals(const StateEval& ev, const StateSpace& sim, const EntrySet& s, int values)
      : Eigen::DenseFunctor<double>(int(s.e.size()), values), ev(ev), sim(sim), s(s) {}
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& fvec) const {
    EntrySet t = s;
    for (size_t k = 0; k < t.e.size(); ++k)
      t.v[k] = to_v(t.e[k], entry_value(sim, t.e[k]), x(Eigen::Index(k)));
    if (StateEval::stable(t.applied_to(sim)))
      ev.residuals_moved(t.e, t.v, &fvec);
    else
      fvec.setConstant(values(), kUnstableResidual);
    return 0;
  }
  const StateEval& ev;
  const StateSpace& sim;
  const EntrySet& s;
};

// The set's entries fitted together from their values in s; s as it was when that does not lower
// its chi2.
EntrySet fit_jointly(const StateEval& ev, const StateSpace& sim, EntrySet s) {
  s.chi2 = ev.chi2(s.applied_to(sim));
  if (!std::isfinite(s.chi2)) return s;
  Eigen::VectorXd x(Eigen::Index(s.e.size()));
  for (size_t k = 0; k < s.e.size(); ++k)
    x(Eigen::Index(k)) = to_x(s.e[k], entry_value(sim, s.e[k]), s.v[k]);
  const SetResiduals f(ev, sim, s, int(2 * ev.points()));
  Eigen::NumericalDiff<SetResiduals> df(f);
  Eigen::LevenbergMarquardt<Eigen::NumericalDiff<SetResiduals>> lm(df);
  lm.setMaxfev(50 * (int(s.e.size()) + 1));
  lm.minimize(x);
  EntrySet t = s;
  for (size_t k = 0; k < t.e.size(); ++k)
    t.v[k] = to_v(t.e[k], entry_value(sim, t.e[k]), x(Eigen::Index(k)));
  t.chi2 = ev.chi2(t.applied_to(sim));
  return t.chi2 < s.chi2 ? t : s;
}

// The residuals of the set s with entry e (in s or not) at coordinate x (moved_responses).
Eigen::VectorXd residuals_at(const StateEval& ev, const StateSpace& sim, const EntrySet& s,
                             const StateEntry& e, double x) {
  std::vector<StateEntry> es = s.e;
  std::vector<double> vs = s.v;
  const double v = to_v(e, entry_value(sim, e), x);
  const auto it =
      std::find_if(es.begin(), es.end(), [&](const StateEntry& y) { return same_entry(e, y); });
  if (it == es.end())
    es.push_back(e), vs.push_back(v);
  else
    vs[size_t(it - es.begin())] = v;
  Eigen::VectorXd res;
  ev.residuals_moved(es, vs, &res);
  return res;
}

// For each candidate, the chi2 a Gauss-Newton step predicts with it and the set's entries moved
// together from `s`: the residuals r0 and each entry's derivative (forward differences of
// kLinearStep in its coordinate), the candidate's derivative and r0 projected off the set's
// derivatives, chi2 = |r0'|^2 - (j' . r0')^2 / |j'|^2. INFINITY where not stable.
std::vector<double> linear_screen(const StateEval& ev, const StateSpace& sim, const EntrySet& s,
                                  const StateSpace& base,
                                  const std::vector<StateEntry>& candidates) {
  Eigen::VectorXd r0;
  std::vector<double> out(candidates.size(), INFINITY);
  if (!ev.residuals(base, &r0)) return out;
  auto derivative = [&](const StateEntry& e, double v) {
    const double x = to_x(e, entry_value(sim, e), v);
    return Eigen::VectorXd((residuals_at(ev, sim, s, e, x + kLinearStep) - r0) / kLinearStep);
  };
  Eigen::MatrixXd Js(r0.size(), Eigen::Index(s.e.size()));
  for (size_t k = 0; k < s.e.size(); ++k) Js.col(Eigen::Index(k)) = derivative(s.e[k], s.v[k]);
  // P projects off the set's derivatives (the identity for the empty set).
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(Js);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(Js.rows(), Js.cols());
  auto off = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
    return Js.cols() ? Eigen::VectorXd(v - Q * (Q.transpose() * v)) : v;
  };
  const Eigen::VectorXd r = off(r0);
  for (size_t c = 0; c < candidates.size(); ++c) {
    if (s.overlaps(sim, candidates[c])) continue;
    const Eigen::VectorXd j = off(derivative(candidates[c], entry_value(sim, candidates[c])));
    const double jj = j.squaredNorm();
    if (!std::isfinite(jj) || j.cwiseAbs().maxCoeff() >= kUnstableResidual / kLinearStep / 2)
      continue;
    const double jr = j.dot(r);
    out[c] = jj > 0 ? r.squaredNorm() - jr * jr / jj : r.squaredNorm();
  }
  return out;
}

// The indices of v, its least value first (a candidate's score by a screen).
std::vector<size_t> least_first(const std::vector<double>& v) {
  std::vector<size_t> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return v[a] < v[b]; });
  return order;
}

// Every set of one more entry than those of `beam`: each new entry screened alone on top of the
// set (fit_alone) and by a Gauss-Newton step with the set's entries (linear_screen); the
// kScreened best by each fitted jointly with the set's entries; the kBeam best, distinct, best
// first.
std::vector<EntrySet> extend(const StateEval& ev, const StateSpace& sim,
                             const std::vector<StateEntry>& candidates,
                             const std::vector<EntrySet>& beam) {
  std::vector<EntrySet> next;
  for (const EntrySet& s : beam) {
    const StateSpace base = s.applied_to(sim);
    const std::vector<double> linear = linear_screen(ev, sim, s, base, candidates);
    std::vector<double> alone(candidates.size(), INFINITY), value(candidates.size(), 0);
    for (size_t c = 0; c < candidates.size(); ++c)
      if (!s.overlaps(sim, candidates[c]))
        std::tie(value[c], alone[c]) = fit_alone(ev, sim, s, base, candidates[c]);
    std::vector<bool> chosen(candidates.size(), false);
    for (const std::vector<double>* by :
         {static_cast<const std::vector<double>*>(&alone), &linear}) {
      const std::vector<size_t> order = least_first(*by);
      for (size_t k = 0; k < std::min(kScreened, order.size()); ++k)
        if (std::isfinite((*by)[order[k]]) && std::isfinite(alone[order[k]]))
          chosen[order[k]] = true;
    }
    for (size_t c = 0; c < candidates.size(); ++c) {
      if (!chosen[c]) continue;
      EntrySet t = s;
      t.e.push_back(candidates[c]), t.v.push_back(value[c]);
      next.push_back(fit_jointly(ev, sim, std::move(t)));
    }
  }
  std::sort(next.begin(), next.end(),
            [](const EntrySet& a, const EntrySet& b) { return a.chi2 < b.chi2; });
  std::vector<EntrySet> out;
  for (EntrySet& s : next) {
    if (out.size() == kBeam) break;
    if (!std::isfinite(s.chi2)) continue;
    if (std::none_of(out.begin(), out.end(), [&](const EntrySet& o) { return o.key() == s.key(); }))
      out.push_back(std::move(s));
  }
  return out;
}

// Set s improved by swaps: each entry in turn taken out and the kScreened candidates the linear
// screen ranks best on the others (each started from its value fitted alone there) fitted jointly
// with them in its place, the best swap taken while it lowers chi2, at most kSwapRounds times. A
// first entry that stood in for several changed ones and steered the sets built on it is so
// replaced once the entries it stood in for are in the set.
EntrySet swapped(const StateEval& ev, const StateSpace& sim,
                 const std::vector<StateEntry>& candidates, EntrySet s) {
  for (int round = 0; round < kSwapRounds && s.e.size() > 1; ++round) {
    EntrySet best = s;
    for (size_t j = 0; j < s.e.size(); ++j) {
      EntrySet rest = s;
      rest.e.erase(rest.e.begin() + std::ptrdiff_t(j));
      rest.v.erase(rest.v.begin() + std::ptrdiff_t(j));
      const StateSpace base = rest.applied_to(sim);
      const std::vector<double> linear = linear_screen(ev, sim, rest, base, candidates);
      const std::vector<size_t> order = least_first(linear);
      for (size_t k = 0; k < std::min(kScreened, order.size()); ++k) {
        const StateEntry& c = candidates[order[k]];
        if (!std::isfinite(linear[order[k]]) || same_entry(c, s.e[j])) continue;
        const auto [v, chi2] = fit_alone(ev, sim, rest, base, c);
        if (!std::isfinite(chi2)) continue;
        EntrySet t = rest;
        t.e.push_back(c), t.v.push_back(v);
        t = fit_jointly(ev, sim, std::move(t));
        if (t.chi2 < best.chi2) best = std::move(t);
      }
    }
    if (!(best.chi2 < s.chi2)) break;
    s = std::move(best);
  }
  return s;
}

// The findings of set s over `pairs` (the X:O pairs): an entry of A, B or C or a named parameter
// a state_parameter;
// a state the simulation lacks, before an input or after an output, a missing lag there; a delay
// it lacks, a time delay there.
std::vector<Finding> findings_of(const StateSpace& sim, const EntrySet& s,
                                 const std::vector<std::string>& pairs) {
  std::vector<Finding> out;
  for (size_t j = 0; j < s.e.size(); ++j) {
    const StateEntry& e = s.e[j];
    if (!e.added()) {
      out.push_back(state_parameter_finding(sim, e, s.v[j], pairs));
      continue;
    }
    Finding f;
    f.cause = e.lag() ? CauseKind::kMissingLag : CauseKind::kTimeDelay;
    f.scope = e.at_input() ? Scope::kInput : Scope::kOutput;
    (e.at_input() ? f.input : f.output) =
        e.at_input() ? sim.inputs[size_t(e.col)] : sim.outputs[size_t(e.row)];
    // What it adds to the state model, named (and, fitted over every pair of the channel, not
    // regrouped): the lag's state, or the delay as its InputDelay or OutputDelay.
    if (e.lag()) {
      f.parameters[Param::kCornerRadS] = 1 / s.v[j];
      f.text_parameters["state"] = with_entry(sim, e, s.v[j]).states.back();
    } else {
      f.parameters[Param::kDelayS] = s.v[j];
      f.text_parameters["delay"] =
          (e.at_input() ? "InputDelay " : "OutputDelay ") + (e.at_input() ? f.input : f.output);
    }
    for (const std::string& pair : pairs) {
      const PairId id = PairId::parse(pair);
      if (e.at_input() ? id.input == f.input : id.output == f.output) f.pairs.push_back(pair);
    }
    out.push_back(std::move(f));
  }
  return out;
}

}  // namespace

void states(DiagnosisRun& r) {
  if (!r.sim.state_space || r.pairs.empty()) return;
  const StateSpace& sim = *r.sim.state_space;
  const auto sim_paths = state_paths(sim);
  if (!sim_paths) return;
  const StateEval ev(r, sim, *sim_paths);
  if (!ev.ok()) return;
  const size_t n = ev.points();
  std::vector<std::string> pairs;
  for (const PairFit& p : r.pairs)
    if (!PairId::parse(p.pair).actuator()) pairs.push_back(p.pair);
  const std::vector<StateEntry> candidates = candidates_of(sim);

  EntrySet none;
  none.chi2 = ev.chi2(sim);
  // beams[k - 1]: the sets of k entries kept, best first.
  std::vector<EntrySet> best{none}, beam{none};
  std::vector<std::vector<EntrySet>> beams;
  for (int size = 1; size <= kMaxEntries; ++size) {
    beam = extend(ev, sim, candidates, beam);
    if (beam.empty()) break;
    beam.front() = swapped(ev, sim, candidates, std::move(beam.front()));
    const auto front = beam.front().key();
    beam.erase(std::remove_if(beam.begin() + 1, beam.end(),
                              [&](const EntrySet& t) { return t.key() == front; }),
               beam.end());
    best.push_back(beam.front());
    beams.push_back(beam);
    // A size that did not earn its place ends the sets taken below: no larger one is searched.
    if (earned(best[best.size() - 2].chi2, best.back().chi2, n, 1) <= 0) break;
  }
  // The largest set each of whose sizes earned its place over the one before, and that the
  // simulation's own factoring takes (as the finding's model will).
  size_t k = 0;
  double e_k = state_error_with(r, {});
  while (k + 1 < best.size()) {
    const StateSpace ss = best[k + 1].applied_to(sim);
    const auto F = ev.ratio(ss);
    if (F.empty() || earned(best[k].chi2, best[k + 1].chi2, n, 1) <= 0 || !state_paths(ss)) break;
    const double e = state_error_with(r, F);
    if (!(e < e_k)) break;
    e_k = e, ++k;
  }
  if (k == 0) return;
  const auto F = ev.ratio(best[k].applied_to(sim));
  for (size_t p = 0; p < r.pairs.size(); ++p)
    for (size_t q = 0; q < r.pairs[p].w.size(); ++q) r.pairs[p].factor[q] *= F[p][q];
  r.state_findings = findings_of(sim, best[k], pairs);
  // The other sets of as many entries that the criterion cannot tell from the one named.
  const double s = std::max(1.0, best[k].chi2 / double(std::max<size_t>(n, 1)));
  for (const EntrySet& t : beams[k - 1]) {
    if (t.key() == best[k].key() || earned(t.chi2, best[k].chi2, n, 1) > 0) continue;
    if (!state_paths(t.applied_to(sim))) continue;
    r.d.state_alternatives.push_back({findings_of(sim, t, pairs), (t.chi2 - best[k].chi2) / s});
  }
}

}  // namespace fralab::diag
