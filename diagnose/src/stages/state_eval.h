// The state model's responses at the prepared pairs' points, for stage 3a (states.cc;
// docs/method/diagnosis.md, 3a): G(jw) = C (jwI - A)^-1 B + D at every distinct frequency (rad/s),
// each input's column and output's row times e^{-jw tau} for the delay a model adds to the
// simulation's there, and the factor G_model / G_sim it puts on each pair; with entries of the
// simulation moved, as a low-rank update of the simulation's resolvent. Residuals are taken in
// the logarithm, ln(measured / model) over the point's relative sigma.
#pragma once

#include <Eigen/Dense>
#include <optional>
#include <utility>
#include <vector>

#include "../causes/state_parameter.h"
#include "stages.h"

namespace fralab::diag {

class StateEval {
 public:
  using Paths = std::vector<std::vector<std::optional<Tf>>>;

  /// The pairs of r whose path the state model sim has (sim_paths, its paths as transfer
  /// functions), the simulation's resolvent at their frequencies; ok() false where A has a mode
  /// outside the open left half plane or a frequency is one of its modes.
  StateEval(const DiagnosisRun& r, const StateSpace& sim, const Paths& sim_paths);
  bool ok() const { return ok_; }

  /// G(jw) = C (jwI - A)^-1 B + D at every distinct frequency, each column and row times
  /// e^{-jw tau} for the delay ss adds to the simulation's at that input or output; false when A
  /// has a mode outside the open left half plane.
  bool responses(const StateSpace& ss, std::vector<Eigen::MatrixXcd>* g) const;

  /// The responses of the simulation with entries e moved to values v (each from its simulated
  /// value by delta), from the simulation's resolvent R = (jwI - A)^-1 (X = C R, Y = R B,
  /// G = X B + D) at each distinct frequency, O(outputs x inputs) a frequency instead of a
  /// factorisation. With B' and C' the moved B and C (their entries added), the moved A
  /// A + U D V^T (U, V the A entries' row and column unit vectors, D their deltas) by Woodbury's
  /// identity:
  ///   G' = C' R B' + D + P D (I - S D)^-1 Q,  P = C' R U, Q = V^T R B', S = V^T R U,
  /// each of C' R B', P, Q and S a lookup in X, Y and R; a named parameter as the entries it sets,
  /// the added lags and delays as factors on their column or row. The moved model's stability is
  /// not checked here (stable()).
  std::vector<Eigen::MatrixXcd> moved_responses(const std::vector<StateEntry>& moved,
                                                const std::vector<double>& moved_v) const;

  /// A's modes in the open left half plane.
  static bool stable(const StateSpace& ss);

  /// On every prepared pair, the factor G_ss / G_sim at each point (1 where the path is not the
  /// state model's); empty when ss is not stable.
  std::vector<std::vector<C>> ratio(const StateSpace& ss) const;
  /// The same from the responses g at every distinct frequency.
  std::vector<std::vector<C>> ratio_of(const std::vector<Eigen::MatrixXcd>& g) const;

  /// The weighted residuals (real and imaginary parts, every pair's points in turn) of the pairs
  /// under ss on top of their factors before this stage, in the logarithm: ln(measured / model)
  /// over the point's relative sigma (sigma / |measured|), as (measured - model) / sigma where
  /// the two are near, and where a change no entry makes leaves a large misfit on some pairs (a
  /// lag the set has not yet taken) not led by their largest points; false when ss is not
  /// stable.
  bool residuals(const StateSpace& ss, Eigen::VectorXd* res) const;
  /// The residuals with entries e at values v (moved_responses; stability unchecked).
  void residuals_moved(const std::vector<StateEntry>& e, const std::vector<double>& v,
                       Eigen::VectorXd* res) const;
  /// The residuals of the factors F on top of the pairs' own.
  void residuals_of(const std::vector<std::vector<C>>& F, Eigen::VectorXd* res) const;
  /// The residuals' sum of squares under ss; INFINITY when ss is not stable.
  double chi2(const StateSpace& ss) const;

  /// Every prepared pair's points.
  size_t points() const { return points_; }
  /// The least and greatest distinct frequency (rad/s).
  std::pair<double, double> band() const;

 private:
  struct PairAt {
    std::pair<Eigen::Index, Eigen::Index> path{-1, -1};  // (output, input) in the state model
    std::vector<size_t> w;                               // each point's distinct frequency
  };
  // The simulation's resolvent (moved_responses); false when a frequency is one of its modes.
  bool resolvent();
  // The added lags and delays of e (post_col per input entry, post_row per output one) on the
  // response.
  static void apply_lags(Eigen::MatrixXcd& g, const std::vector<StateEntry>& e,
                         const std::vector<C>& post_col, const std::vector<C>& post_row);

  const DiagnosisRun& r_;
  const StateSpace& sim_;
  std::vector<Eigen::MatrixXcd> R_, X_, Y_, G_;
  std::vector<double> w_;
  std::vector<PairAt> at_;
  std::vector<Eigen::MatrixXcd> g_sim_;
  size_t points_ = 0;  // every prepared pair's points
  bool ok_ = false;
};

}  // namespace fralab::diag
