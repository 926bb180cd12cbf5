// The state-space model of an operating point (the report's recipe, Section I "Form of the model"):
// the states are the distinct poles of the transfer matrix, each counted once.
//
// 1. Every converged path's poles are replaced by their cluster means (transfer_matrix.h); its
//    residues are refitted by weighted linear least squares on its data (poles fixed, the path's
//    delay kept): G_oi(s) = d_oi + sum_k r_oik / (s - p_k).
//    (Paths that reached the maximum order or have no response are not refitted; their data enter
//    2.)
// 2. For each cluster k the residue matrix R_k (outputs x inputs) is reduced to rank one,
//    R_k ~ c_k b_k^T: one state per real pole, two (real modal form) per pair. The SVD's factors
//    (real for a real pole) start a fit of c, b and the d of biproper paths to the data themselves:
//    min sum over paths and points of |G_model - G|^2 / sigma^2 (1/|G|^2 without sigma), by
//    alternating least squares (c with b fixed, output by output, then b with c fixed; each
//    half-step an exact minimum, so the misfit never rises). The SVD weighs the residues by their
//    size in each sensor's units: where a cluster's residues are not rank one (the J85's paths
//    have each their own rotor pole near 3 rad/s; one cluster), it keeps the large entries and
//    loses the small sensors' (DPP3 in psi, 1e-4 of P3's): on the J85 lab's multisine run the
//    SVD's factors miss Wf:P3 by 9e4 chi2 per point, the fitted ones by 2.3. Every measured path
//    but a failed fit is in the fit (those that reached the maximum order with their fit's delay,
//    those with no response on their data, noise, by their sigma): the rank-one products put
//    response into every path, and a path left out is predicted by factors nothing holds there.
//    Each sweep's step is extrapolated (doubled) while that lowers the misfit further: alternating
//    least squares crawls along flat valleys (the J85 run: 2.1e7 -> 2800 in 500 sweeps, 0.3 s; 3700
//    without the extrapolation).
//    Then Gilbert's realisation where the data need it (this extends the report's recipe): a
//    cluster whose residues are not rank one gets one more component c' b'^T on the same pole
//    (rank(R_k) components in all, each a state, two for a pair), greedily, the best cluster at a
//    time, while that lowers the criterion misfit + ln(2N) per real parameter the component adds
//    ((outputs + inputs - 1), twice for a pair; N the complex points over all paths, as the order
//    search's penalty; with sigma on every path the misfit is chi2, otherwise 2N ln(sse / 2N) with
//    the sse floored at 1e-18 of the data's weighted energy so that noise-free data do not buy
//    rounding). A cluster's rank is at most the number of distinct outputs and of inputs among
//    its member paths, and `max_rank`. A candidate starts from the residues each path would still
//    take on that pole (each fitted to what the model leaves of its data, sized by the chi2 it
//    would remove, the first right singular vector as b') and is compared with the model without
//    it after the same `rank_trial_sweeps` sweeps each (the creep of alternating least squares is
//    then not credited to the candidate); the one taken is fitted to the end. On the J85's paths
//    at 2 % noise (state_model_test) IGV:P3, whose rotor pole shares a cluster with three others,
//    goes 171 -> 0.75 chi2 per point with two more states.
// 3. x' = A x + B u, y = C x + D u, with A block-diagonal (p for a real pole, [[s, -w], [w, s]] for
//    a pair s +- jw; a cluster of rank r has r such blocks); each path's delay is kept beside the
//    model (delay_s[output][input]).
// 4. Checked against the data, every path with a measured curve (in the model or not):
//    - error: the rms of |ln(G_model / G_measured)| (as the diagnosis measures it) over the points
//      measured to better than 30 % (sigma <= 0.3 |G|, the fit's own no-response test; every
//      valid point when the curve has no sigma). Points below that are noise, where the log
//      ratio measures the noise, not the model (on the J85 lab's multisine run, the fits' own
//      error over every point is 0.6-1.9 on five paths whose clear points they fit to 3-26 %).
//      No such point (a path with no response): no error; the check is then the next figure.
//    - chi2 per point: mean |G_model - G|^2 / sigma^2 over the valid points, beside the same
//      figure for the path's own fit (a zero response for no_response): about 1 when the model
//      is as good as the noise, what the state model's pinned poles and rank-one residues cost
//      where it is larger than the fit's (< 0 without sigma).
//    The total is the rms of the errors of the paths in the model (converged fits).
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
