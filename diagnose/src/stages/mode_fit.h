// Internal to the diagnosis' stage 3b (modes.cc): a mode of a scope, its move fitted over the
// scope's pairs (the factor D_from / D_to or the mode shape kept), and the moves taken so far on
// the pairs' factors, for the search that modes.cc runs (docs/method/diagnosis.md, "The stages",
// 3b). chi2 here is taken in the logarithm with each pair's gain left free. Frequencies rad/s.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include "stages.h"

namespace fralab::diag::mode {

inline constexpr double kSearchRel = 0.1;  // ln wn searched within +-this of the simulated
inline constexpr double kZetaSpan = 10;    // the damping within a factor of this of the simulated
inline constexpr int kMaxModes = 12;       // modes moved at most
inline constexpr int kRounds = 8;          // frequency / damping alternations at most
inline constexpr int kBackfitRounds = 2;   // each mode fitted again with the others in place
inline constexpr double kBandShare = 0.1;  // a frequency move below this share of the band is none
inline constexpr int kMaxGrid = 400;       // the frequency grid's points at most (steps >= 0.05 %)
inline constexpr int kBrentBits = 20;      // Brent's method's precision (bits)
// A mode keeps its place among the modes of its pairs: its frequency stays this many times the
// lighter damping (relative) from each neighbour's frequency as it now is (ModeRange).
inline constexpr double kApartZetas = 0.25;

struct SharedMode {
  size_t id = 0;  // its index among the stage's candidates
  Root root;
  Scope scope = Scope::kPlant;
  std::string input, output;
  std::vector<size_t> pairs;  // into r.pairs
  // Per pair, for the move with the shape kept: the path's residue at the mode and its rational
  // part at the pair's points (empty when a path does not hold the mode as a simple pole).
  std::vector<C> residue;
  std::vector<std::vector<C>> rational;
  std::vector<std::vector<C>> from_factor;  // per pair, D_from at its points
};

// A mode moved: its parameters, its factor on each of its pairs, chi2 over them, k.
struct MovedMode {
  double wn = 0, zeta = 0, chi2 = INFINITY;
  int k = 1;
  std::vector<std::vector<C>> F;
  bool residues_kept = false;  // the move keeps each path's mode shape (mode_residues.h)
};

// Where a mode's ln wn is searched: within +-kSearchRel of the simulated, and between the
// neighbours of its pairs as they now are (two modes moved onto one frequency are one mode
// counted twice, whose split the data cannot tell), its damping within a factor kZetaSpan. Each
// neighbour bounds it on the side the simulation has it, or on the other side where the search
// took the two past each other (`crossed`, lower id first); `ignore` bounds it not at all.
struct ModeRange {
  double lo = 0, hi = 0, lz_lo = 0, lz_hi = 0;
  double clamp(double x) const { return std::clamp(x, lo, hi); }
  double clamp_z(double x) const { return std::clamp(x, lz_lo, lz_hi); }
};

using Crossed = std::set<std::pair<size_t, size_t>>;

/// Whether modes a and b share a pair (each bounds the other's search: ModeRange).
bool share_pairs(const SharedMode& a, const SharedMode& b);

ModeRange range_of(const std::vector<SharedMode>& all, const std::vector<Root>& now, size_t id,
                   const Crossed& crossed, std::optional<size_t> ignore);

// The moves taken so far, per pair of r: the pair's factor is base x mult x (1 + add), base its
// factor before the stage. A move by the factor D_from / D_to multiplies (pole-zero factors
// compose by product); a move with the mode shape kept adds its term to the path's partial
// fractions, (R + delta) / R = 1 + delta / R with delta = r' / (s - p') - r / (s - p) + conj:
// modes add, and the product of two neighbours' factors would count their overlap twice (a few
// per cent near two modes whose half-power bands overlap).
struct Moves {
  std::vector<std::vector<C>> base, mult, add;
  explicit Moves(const DiagnosisRun& r) {
    for (const PairFit& p : r.pairs) {
      base.push_back(p.factor);
      mult.emplace_back(p.factor.size(), C(1));
      add.emplace_back(p.factor.size(), C(0));
    }
  }
  // Pair k's factor at point q with the move F on top (shape_kept: F = 1 + delta / R).
  C with(size_t k, size_t q, C F, bool shape_kept) const {
    return shape_kept ? base[k][q] * mult[k][q] * (C(1) + add[k][q] + (F - C(1)))
                      : base[k][q] * mult[k][q] * (C(1) + add[k][q]) * F;
  }
  C now(size_t k, size_t q) const { return base[k][q] * mult[k][q] * (C(1) + add[k][q]); }
};

/// The move to `to` on each of the mode's pairs (shape_kept: its mode shape kept).
std::vector<std::vector<C>> move_factors(const DiagnosisRun& r, const SharedMode& m, const Root& to,
                                         bool shape_kept);

/// chi2 over the mode's pairs with the move F on top of their factors (none: their factors as
/// they are).
double chi2_with(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                 const std::vector<std::vector<C>>& F = {}, bool shape_kept = false);

/// chi2 over the pairs of the modes `ms` (each once), their factors as they now are.
double chi2_over(const DiagnosisRun& r, const Moves& mv, const std::vector<SharedMode>& ms);

/// The points over the mode's pairs.
size_t points_over(const DiagnosisRun& r, const SharedMode& m);
/// The points over the pairs of the modes `ms`, each pair once (as chi2_over counts them).
size_t points_over(const DiagnosisRun& r, const std::vector<SharedMode>& ms);

/// The mode's move fitted within g, the other moves of mv in place: the factor's, or the one
/// with the mode shape kept where its chi2 is lower (always, shape_only).
MovedMode fit_mode(const DiagnosisRun& r, const Moves& mv, const SharedMode& m, const ModeRange& g,
                   bool shape_only);

/// The error metric over the mode's pairs, their current factors with the move F (empty: none).
double error_with(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                  const std::vector<std::vector<C>>& F, bool shape_kept);

/// The move f on (or, inverse, off) each of the mode's pairs (Moves), their factors updated.
void apply_factor(DiagnosisRun& r, Moves& mv, const SharedMode& m, const MovedMode& f,
                  bool inverse);

/// Every pair's factor as the moves mv have it.
void restore_factors(DiagnosisRun& r, const Moves& mv);

/// Some moves took the factor form where a mode shape is known.
bool forms_mixed(const std::vector<SharedMode>& taken, const std::vector<MovedMode>& fits);

/// The taken move whose removal raises chi2 over its pairs least beyond its penalty (the others
/// as they now are), and that gain.
std::pair<size_t, double> least_useful(DiagnosisRun& r, Moves& mv,
                                       const std::vector<SharedMode>& taken,
                                       const std::vector<MovedMode>& fits);

// The candidate of `left` whose move lowers chi2 most beyond its penalty and lowers its pairs'
// error (left.size() when none), and its move; a candidate tried that does not is marked unworthy.
template <class Fit>
std::pair<size_t, MovedMode> best_candidate(const DiagnosisRun& r, const Moves& mv,
                                            const std::vector<SharedMode>& left,
                                            std::vector<bool>& worth, const Fit& fit) {
  size_t best = left.size();
  MovedMode best_fit;
  double best_gain = 0;
  for (size_t c = 0; c < left.size(); ++c) {
    if (!worth[c]) continue;
    const SharedMode& m = left[c];
    const double c0 = chi2_with(r, mv, m);
    MovedMode f = fit(m);
    const double gain = earned(c0, f.chi2, points_over(r, m), f.k);
    worth[c] =
        gain > 0 && error_with(r, mv, m, f.F, f.residues_kept) < error_with(r, mv, m, {}, false);
    if (worth[c] && gain > best_gain) best = c, best_fit = std::move(f), best_gain = gain;
  }
  return {best, std::move(best_fit)};
}

}  // namespace fralab::diag::mode
