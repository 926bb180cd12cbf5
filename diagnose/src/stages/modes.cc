// Stage 3b, modes (docs/method/diagnosis.md, "The stages", 3b): a lightly damped pair of the
// simulation that every path of a scope holds (a structure's mode, seen by every sensor; a mode of
// one output's or one input's paths) is moved once, over all those pairs together, before any
// pair is diagnosed alone. Each pair's own fit would split it, or miss it where several modes
// moved and none alone removes a quarter of the pair's chi2.
//
// Candidates: pairs (zeta <= kLightZeta) of the paths' poles inside the band of the pairs that
// hold them, held (wn within kSameRoot) by every X:O pair of the plant, of one output, or of one
// input (at least two pairs). A move is the factor D_from / D_to on each pair (ln wn by a grid
// over +-kSearchRel, between the neighbours of its pairs (ModeRange), in steps of a third of the
// damping, then the damping, then the two alternately by Brent's method), or, when its chi2 is
// lower, the same move with each path's mode shape kept (mode_residues.h; such moves of several
// modes on one path add, as the modes' terms do, where the factors multiply: Moves). chi2 here is
// taken in the logarithm with each pair's gain left free (pair_log_chi2): a calibration or a path
// gain, fitted by the later stages, is not taken up by a mode, and a wrong neighbour's peak does
// not flatten the mode being fitted. Greedy, while a move lowers chi2 by more than k ln 2N in units
// of its pairs' misfit level s = max(1, chi2 / N) and lowers their error; then each mode fitted
// again with the others in place, the forms compared whole (every move with its shape kept, kept
// when chi2 is lower), neighbours whose bands overlap fitted again in the other order and past
// each other (ModeSearch::other_orders), and the least useful dropped while it does not earn its
// place. A frequency move below kBandShare of the half-power band is a damping_error.
#include <algorithm>
#include <cmath>
#include <optional>

#include "../causes/mode_residues.h"
#include "mode_fit.h"
#include "stages.h"

namespace fralab::diag {
namespace {

using namespace mode;

constexpr double kLightZeta = 0.2;  // a mode is lighter than this
constexpr double kSameRoot = 1e-3;  // a path holds the mode: a pole within this (relative)

// The residues and rational parts of m's paths (SharedMode), once per mode.
void prepare_residues(const DiagnosisRun& r, SharedMode& m) {
  for (size_t k : m.pairs)
    m.from_factor.push_back(factor_of(r.pairs[k].w, [&](C s) { return m.root.factor(s); }));
  for (size_t k : m.pairs) {
    const PairFit& p = r.pairs[k];
    const ModelPath* mp = r.sim.path(p.output, p.input);
    const auto res = mp ? pair_residue(mp->tf, m.root) : std::nullopt;
    if (!res) {
      m.residue.clear(), m.rational.clear();
      return;
    }
    m.residue.push_back(*res);
    m.rational.push_back(factor_of(p.w, [&](C s) { return mp->tf.rational(s); }));
  }
}

// Two pairs are one mode when their frequencies agree within kSameRoot.
bool same_root(const Root& a, const Root& b) {
  return a.pair && b.pair && std::abs(a.wn - b.wn) <= kSameRoot * b.wn;
}

bool holds(const Model& m, const PairFit& p, const Root& root) {
  std::vector<Root> v;
  if (const ModelPath* mp = m.path(p.output, p.input)) v = mp->tf.poles;
  const int o = m.output_index(p.output);
  if (o >= 0 && m.outputs[size_t(o)].sensor)
    v.insert(v.end(), m.outputs[size_t(o)].sensor->poles.begin(),
             m.outputs[size_t(o)].sensor->poles.end());
  return std::any_of(v.begin(), v.end(), [&](const Root& q) { return same_root(q, root); });
}

// The scope whose X:O pairs are exactly `holders` (at least two), or nullopt.
std::optional<SharedMode> scope_of(const DiagnosisRun& r, const std::vector<size_t>& holders) {
  if (holders.size() < 2) return std::nullopt;
  auto exactly = [&](const std::function<bool(const PairFit&)>& sel) {
    size_t n = 0;
    for (const PairFit& p : r.pairs) n += !p.output.empty() && sel(p) ? 1 : 0;
    return n == holders.size() &&
           std::all_of(holders.begin(), holders.end(), [&](size_t k) { return sel(r.pairs[k]); });
  };
  SharedMode m;
  m.pairs = holders;
  if (exactly([](const PairFit&) { return true; })) return m;
  const PairFit& first = r.pairs[holders[0]];
  if (exactly([&](const PairFit& p) { return p.output == first.output; })) {
    m.scope = Scope::kOutput, m.output = first.output;
    return m;
  }
  if (exactly([&](const PairFit& p) { return p.input == first.input; })) {
    m.scope = Scope::kInput, m.input = first.input;
    return m;
  }
  return std::nullopt;
}

std::vector<SharedMode> shared_modes(const DiagnosisRun& r) {
  std::vector<Root> seen;
  std::vector<SharedMode> out;
  for (const PairFit& p : r.pairs) {
    if (p.output.empty()) continue;
    std::vector<Root> roots;
    if (const ModelPath* mp = r.sim.path(p.output, p.input)) roots = mp->tf.poles;
    for (const Root& root : roots) {
      if (!root.pair || !(root.zeta > 0 && root.zeta <= kLightZeta)) continue;
      if (std::any_of(seen.begin(), seen.end(), [&](const Root& q) { return same_root(q, root); }))
        continue;
      seen.push_back(root);
      std::vector<size_t> holders;
      double lo = INFINITY, hi = 0;
      for (size_t k = 0; k < r.pairs.size(); ++k) {
        const PairFit& q = r.pairs[k];
        if (q.output.empty() || q.w.empty() || !holds(r.sim, q, root)) continue;
        holders.push_back(k);
        lo = std::min(lo, q.w.front()), hi = std::max(hi, q.w.back());
      }
      if (!(root.wn >= lo && root.wn <= hi)) continue;
      if (auto m = scope_of(r, holders)) {
        m->id = out.size();
        m->root = root;
        prepare_residues(r, *m);
        out.push_back(*m);
      }
    }
  }
  return out;
}

// A damping change alone: the frequency moved by less than a tenth of the mode's half-power
// band (zeta, relative), or its move does not lower chi2 by one penalty in units of the misfit
// level. The finding is then the pair's damping_error, whose parameter is the damping.
bool damping_only(const DiagnosisRun& r, const Moves& mv, const SharedMode& m, const MovedMode& f) {
  if (f.k < 2) return false;
  if (std::abs(f.wn / m.root.wn - 1) < kBandShare * m.root.zeta) return true;
  const double c_from =
      chi2_with(r, mv, m, move_factors(r, m, Root::Pair(m.root.wn, f.zeta), f.residues_kept),
                f.residues_kept);
  return earned(c_from, f.chi2, points_over(r, m), 1) <= 0;
}

Finding finding_of(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                   const MovedMode& fit) {
  Finding f;
  f.scope = m.scope;
  f.input = m.input;
  f.output = m.output;
  if (damping_only(r, mv, m, fit)) {
    f.cause = CauseKind::kDampingError;
    f.parameters = {
        {Param::kWnRadS, m.root.wn}, {Param::kFromZeta, m.root.zeta}, {Param::kToZeta, fit.zeta}};
    if (fit.residues_kept) f.text_parameters["form"] = "residue";
  } else {
    f.cause = CauseKind::kPoleShift;
    f.parameters = {{Param::kFromRadS, m.root.wn},
                    {Param::kToRadS, fit.wn},
                    {Param::kFromZeta, m.root.zeta},
                    {Param::kToZeta, fit.zeta},
                    {Param::kZeta, fit.zeta}};
    if (fit.residues_kept) f.text_parameters["form"] = "residue";
  }
  for (size_t k : m.pairs) f.pairs.push_back(r.pairs[k].pair);
  return f;
}

// The moves the stage takes, applied to the pairs' factors.
struct Pass {
  std::vector<SharedMode> taken;
  std::vector<MovedMode> fits;
  Moves mv;
};

// The search for the moves: greedy, backfitted, the forms compared, neighbours taken in the
// other order, the least useful dropped (moves()).
class ModeSearch {
 public:
  ModeSearch(DiagnosisRun& r, std::vector<SharedMode> left)
      : r_(r), all_(left), left_(std::move(left)), mv_(r) {
    for (const SharedMode& m : all_) now_.push_back(m.root);
  }

  Pass run() {
    greedy();
    // Backfitting: each mode fitted again with every other one in place (modes moved towards
    // each other share their band, and the first one taken held part of the next).
    if (taken_.size() > 1) backfit();
    compare_forms();
    other_orders();
    drop_least_useful();
    return {std::move(taken_), std::move(fits_), std::move(mv_)};
  }

 private:
  MovedMode fit(const SharedMode& m) const {
    return fit_mode(r_, mv_, m, range_of(all_, now_, m.id, crossed_, ignore_), shape_only_);
  }
  void take(const SharedMode& m, const MovedMode& f, bool inverse) {
    apply_factor(r_, mv_, m, f, inverse);
    now_[m.id] = inverse ? m.root : Root::Pair(f.wn, f.zeta);
  }
  void refit(size_t j) {
    take(taken_[j], fits_[j], true);
    fits_[j] = fit(taken_[j]);
    take(taken_[j], fits_[j], false);
  }
  // Each taken mode fitted again with the others in place, kBackfitRounds times.
  void backfit() {
    for (int round = 0; round < kBackfitRounds; ++round)
      for (size_t j = 0; j < taken_.size(); ++j) refit(j);
  }

  // While a candidate's move earns its place, the best is taken. A candidate whose move did not
  // earn its place in a round is skipped in the next ones (each round refits every candidate it
  // tries); when none of the others earns its place, every candidate is tried again once before
  // the search stops (a neighbour's move can make one worth it).
  void greedy() {
    std::vector<bool> worth(left_.size(), true);
    bool full = true;
    while (int(taken_.size()) < kMaxModes && !left_.empty()) {
      auto [best, best_fit] =
          best_candidate(r_, mv_, left_, worth, [&](const SharedMode& m) { return fit(m); });
      if (best == left_.size()) {
        if (full) break;
        full = true;
        worth.assign(left_.size(), true);
        continue;
      }
      full = false;
      take(left_[best], best_fit, false);
      taken_.push_back(left_[best]);
      fits_.push_back(std::move(best_fit));
      left_.erase(left_.begin() + long(best));
      worth.erase(worth.begin() + long(best));
    }
  }

  // The forms compared whole: a mode fitted alone beside a neighbour sized wrong may take the
  // factor form, which then holds the neighbour where it is (modes moved with their shapes add;
  // a factor multiplies the neighbour's term too). Every move refitted with its shape kept, the
  // same rounds; kept when chi2 over the moved modes' pairs is lower than the mixed forms'.
  void compare_forms() {
    if (taken_.size() < 2 || !forms_mixed(taken_, fits_)) return;
    const State was = state();
    const double c_mixed = chi2_over(r_, mv_, taken_);
    shape_only_ = true;
    backfit();
    if (!(chi2_over(r_, mv_, taken_) < c_mixed)) restore(was);
  }

  // Neighbours in the other order: a taken mode and its neighbour on either side (a candidate
  // sharing its pairs, none between them, their half-power bands as they now are overlapping:
  // ln of their frequencies' ratio below the sum of their dampings) are fitted again, the
  // one fitted second first, then backfitted together. Where two modes moved towards each
  // other, the first one taken alone covers both peaks and bars the second from its place (each
  // stays on its side of the other). Then the two past each other, either fitted first (the
  // other then bounded on the far side of it), as where two modes moved across each other.
  // Each is kept when chi2 over their pairs is lower by more than the penalty of the parameters
  // it adds.
  void other_orders() {
    for (size_t j = 0; j < taken_.size(); ++j)
      for (const SharedMode* n : neighbours(taken_[j])) {
        const auto q = taken_index(n->id);
        if (q && *q < j) continue;  // tried from the other one
        const size_t a = taken_[j].id, b = n->id;
        try_pair(b, a, false);
        if (crossed_.count({std::min(a, b), std::max(a, b)})) continue;
        try_pair(a, b, true);
        try_pair(b, a, true);
      }
  }

  // The candidates next to m on either side (sharing its pairs, none between them) whose
  // half-power band overlaps m's.
  std::vector<const SharedMode*> neighbours(const SharedMode& m) const {
    const SharedMode* below = nullptr;
    const SharedMode* above = nullptr;
    for (const SharedMode& n : all_) {
      if (n.id == m.id || !share_pairs(m, n)) continue;
      if (n.root.wn < m.root.wn && (!below || n.root.wn > below->root.wn)) below = &n;
      if (n.root.wn > m.root.wn && (!above || n.root.wn < above->root.wn)) above = &n;
    }
    std::vector<const SharedMode*> out;
    const Root& x = now_[m.id];
    for (const SharedMode* n : {below, above})
      if (n && std::abs(std::log(x.wn / now_[n->id].wn)) < x.zeta + now_[n->id].zeta)
        out.push_back(n);
    return out;
  }

  // The moves of modes `first` and `second` taken off and fitted again in that order (crossing:
  // `first` fitted as if `second` were not there, `second` then on its far side), then backfitted
  // together; kept when chi2 over their pairs earns the parameters added, else undone.
  void try_pair(size_t first, size_t second, bool crossing) {
    const State was = state();
    const std::vector<SharedMode> both = {all_[first], all_[second]};
    const double c0 = chi2_over(r_, mv_, both);
    const int k0 = params_of(first) + params_of(second);
    for (size_t id : {first, second}) untake(id);
    if (crossing) crossed_.insert({std::min(first, second), std::max(first, second)});
    for (size_t id : {first, second}) {
      if (crossing) ignore_ = id == first ? std::optional<size_t>(second) : std::nullopt;
      MovedMode f = fit(all_[id]);
      take(all_[id], f, false);
      taken_.push_back(all_[id]);
      fits_.push_back(std::move(f));
    }
    // Backfitted until chi2 over the two falls by less than a thousandth a round.
    for (int round = 0; round < kRounds; ++round) {
      const double c = chi2_over(r_, mv_, both);
      for (size_t j = taken_.size() - 2; j < taken_.size(); ++j) refit(j);
      if (round + 1 >= kBackfitRounds && !(chi2_over(r_, mv_, both) < (1 - 1e-3) * c)) break;
    }
    const int k1 = params_of(first) + params_of(second);
    const size_t n = points_over(r_, both);
    if (!(earned(c0, chi2_over(r_, mv_, both), n, std::max(0, k1 - k0)) > 0)) restore(was);
  }

  std::optional<size_t> taken_index(size_t id) const {
    for (size_t j = 0; j < taken_.size(); ++j)
      if (taken_[j].id == id) return j;
    return std::nullopt;
  }
  int params_of(size_t id) const {
    const auto j = taken_index(id);
    return j ? fits_[*j].k : 0;
  }
  // The mode's move taken off (when taken), the mode back among those left.
  void untake(size_t id) {
    if (const auto j = taken_index(id)) {
      take(taken_[*j], fits_[*j], true);
      taken_.erase(taken_.begin() + long(*j));
      fits_.erase(fits_.begin() + long(*j));
      return;
    }
    left_.erase(
        std::find_if(left_.begin(), left_.end(), [&](const SharedMode& m) { return m.id == id; }));
  }

  // Each must still earn its place with the others in place, as it did when taken: the least
  // useful is dropped while its removal raises chi2 by no more than its penalty in units of the
  // misfit level (a small move that made up for a neighbour taken before it was refitted), and
  // the rest fitted again.
  void drop_least_useful() {
    while (!taken_.empty()) {
      const auto [worst, worst_gain] = least_useful(r_, mv_, taken_, fits_);
      if (worst_gain > 0) break;
      take(taken_[worst], fits_[worst], true);
      std::erase_if(crossed_, [&](const auto& x) {  // back where the simulation has it
        return x.first == taken_[worst].id || x.second == taken_[worst].id;
      });
      left_.push_back(taken_[worst]);
      taken_.erase(taken_.begin() + long(worst));
      fits_.erase(fits_.begin() + long(worst));
      for (size_t j = 0; j < taken_.size(); ++j) refit(j);
    }
  }

  struct State {
    Moves mv;
    std::vector<MovedMode> fits;
    std::vector<Root> now;
    std::vector<SharedMode> taken, left;
    bool shape_only;
    Crossed crossed;
  };
  State state() const { return {mv_, fits_, now_, taken_, left_, shape_only_, crossed_}; }
  void restore(const State& s) {
    mv_ = s.mv, fits_ = s.fits, now_ = s.now, taken_ = s.taken, left_ = s.left;
    shape_only_ = s.shape_only, crossed_ = s.crossed;
    restore_factors(r_, mv_);
  }

  DiagnosisRun& r_;
  const std::vector<SharedMode> all_;
  std::vector<SharedMode> left_, taken_;
  std::vector<MovedMode> fits_;
  std::vector<Root> now_;  // each candidate's pair as it now is
  Moves mv_;
  bool shape_only_ = false;       // every move with its mode shape kept (compare_forms)
  Crossed crossed_;               // pairs of candidates the search took past each other
  std::optional<size_t> ignore_;  // a candidate the fit under way does not bound by
};

}  // namespace

void modes(DiagnosisRun& r) {
  Pass pass = ModeSearch(r, shared_modes(r)).run();
  // Each finding judged without its own factor on its pairs (the others in place).
  for (size_t j = 0; j < pass.taken.size(); ++j) {
    apply_factor(r, pass.mv, pass.taken[j], pass.fits[j], true);
    r.mode_findings.push_back(finding_of(r, pass.mv, pass.taken[j], pass.fits[j]));
    apply_factor(r, pass.mv, pass.taken[j], pass.fits[j], false);
  }
}

double earned(double c0, double c, size_t n, int k) {
  const double s = std::max(1.0, c / double(std::max<size_t>(n, 1)));
  return (c0 - c) / s - k * std::log(2.0 * double(n));
}

}  // namespace fralab::diag
