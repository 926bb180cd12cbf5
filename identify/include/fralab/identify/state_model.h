// The state-space model of an operating point (the report's recipe, Section I "Form of the model"):
// the states are the distinct poles of the transfer matrix, each counted once. In: the transfer
// matrix (its fits and pole clusters, transfer_matrix.h) and each path's measured curve. Out:
// 1. Each converged path's residues on its clusters' mean poles, by weighted linear least squares
//    (poles fixed, the path's delay kept): G_oi(s) = d_oi + sum_k r_oik / (s - p_k).
// 2. Per cluster k, R_k ~ c_k b_k^T, started from the SVD's factors and fitted to the data by
//    alternating least squares: min sum |G_model - G|^2 / sigma^2 (1/|G|^2 without sigma).
// 3. More components c' b'^T on a cluster whose residues are not rank one (Gilbert's realisation,
//    at most max_rank), while misfit + ln(2N) per real parameter added falls. Then
//    x' = A x + B u, y = C x + D u, A block-diagonal: p for a real pole, [[s, -w], [w, s]] for a
//    pair s +- jw, one block per component; each path's delay beside it (delay_s[output][input]).
// 4. The check of every path with a measured curve: error = rms |ln(G_model / G_measured)| over
//    the points with sigma <= 0.3 |G| (every valid point without sigma; no such point: error < 0)
//    and chi2 per point = mean |G_model - G|^2 / sigma^2 over the valid points (< 0 without
//    sigma), beside the path's own fit's; the total error is the rms of the converged paths'.
// Units: poles and w in rad/s, delays in seconds, each path in its own output-over-input units.
// Paths that reached the maximum order or have no response are not refitted in 1., but their data
// enter 2.; a failed fit's data stay out of 2.
// Method: docs/method/state-model.md ("The state model").
#pragma once

#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "fralab/core/error.h"
#include "fralab/identify/transfer_matrix.h"

namespace fralab {

struct StateModelOptions {
  int max_sweeps = 500;        // the factors' fit: alternating sweeps (c, then b) at most (0: none)
  double rel_tol = 1e-9;       // it stops when a sweep lowers the misfit by less than this fraction
  int max_rank = 4;            // components per cluster at most (1: the report's rank-one residues)
  int rank_trial_sweeps = 50;  // sweeps a candidate component (and the model without it) is given
  void validate() const {
    if (max_sweeps < 0) throw InputError("state model: max_sweeps must be >= 0");
    if (!(rel_tol >= 0)) throw InputError("state model: rel_tol must be >= 0");
    if (max_rank < 1) throw InputError("state model: max_rank must be >= 1");
    if (rank_trial_sweeps < 1) throw InputError("state model: rank_trial_sweeps must be >= 1");
  }
};

// The check of one path (see 4. above).
struct StateModelPathCheck {
  std::string fit_status;      // the path's fit ("converged": in the model)
  int points = 0;              // valid points with |G| > 0
  int clear = 0;               // of which measured to better than 30 % (all without sigma)
  double error = -1;           // rms |ln(G_model / G_measured)| over the clear points; < 0: none
  double chi2_per_point = -1;  // the model: mean |G_model - G|^2 / sigma^2; < 0: no sigma
  double fit_chi2_per_point = -1;  // the path's own fit, the same way
  bool model_silent = false;       // the model is exactly 0 at a clear point (error: none)
};

struct StateModel {
  std::vector<std::string> inputs, outputs;
  Eigen::MatrixXd A, B, C, D;
  Eigen::MatrixXd delay_s;  // outputs x inputs
  int order = 0;
  std::map<std::string, double> path_error;  // "input:output" -> check.error, paths that have one
  std::map<std::string, StateModelPathCheck> path_check;  // "input:output", every path with data
  double error = 0;                // rms of the errors of the paths in the model (converged fits)
  std::vector<double> rank1_loss;  // per cluster: 1 - s1^2 / sum s^2 of R_k (the refitted residues)
  std::vector<int> rank;           // per cluster: its components (states: rank, twice for a pair)
  std::vector<Root> poles;         // per cluster: its pole (the cluster's mean)
  // The factors' fit (2.): the weighted misfit sum |G_model - G|^2 / sigma^2 of the SVD's factors
  // and of the fitted ones, and the sweeps it took.
  double start_chi2 = 0, fit_chi2 = 0;
  int sweeps = 0;  // over the fits of the components taken (the candidates' trials not counted)

  /// Frequency response output o / input i at w rad/s (delay included).
  std::complex<double> at(int o, int i, double w) const;
};

/// `data`: the measured curve of each fitted path, keyed "input:output".
StateModel build_state_model(const TransferMatrix& m,
                             const std::map<std::string, std::vector<FrdPoint>>& data,
                             const StateModelOptions& opt = {});

Json state_model_json(const StateModel& s);

/// The "State model" section of transfer_matrix.md: order, total error and each path's check.
std::string state_model_markdown(const StateModel& s);

}  // namespace fralab
