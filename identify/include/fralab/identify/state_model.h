// The state-space model of an operating point (the report's recipe, Section I "Form of the model"):
// the states are the distinct poles of the transfer matrix, each counted once.
//
// 1. Every fitted path's poles are replaced by their cluster means (transfer_matrix.h); its
//    residues are refitted by weighted linear least squares on its data (poles fixed, the path's
//    delay kept): G_oi(s) = d_oi + sum_k r_oik / (s - p_k).
// 2. For each cluster k the residue matrix R_k (outputs x inputs) is reduced to rank one by SVD,
//    R_k ~ c_k b_k^T: one state per real pole, two (real modal form) per pair.
// 3. x' = A x + B u, y = C x + D u, with A block-diagonal (p for a real pole, [[s, -w], [w, s]] for
//    a pair s +- jw); each path's delay is kept beside the model (delay_s[output][input]).
// 4. Checked against the data: per path and in total, the rms of |ln(G_model / G_measured)|, as
//    the diagnosis measures it.
#pragma once

#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "fralab/identify/transfer_matrix.h"

namespace fralab {

struct StateModel {
  std::vector<std::string> inputs, outputs;
  Eigen::MatrixXd A, B, C, D;
  Eigen::MatrixXd delay_s;  // outputs x inputs
  int order = 0;
  std::map<std::string, double> path_error;  // "input:output" -> error vs data
  double error = 0;                          // all paths together
  std::vector<double> rank1_loss;            // per cluster: 1 - s1^2 / sum s^2 of R_k

  /// Frequency response output o / input i at w rad/s (delay included).
  std::complex<double> at(int o, int i, double w) const;
};

/// `data`: the measured curve of each fitted path, keyed "input:output".
StateModel build_state_model(const TransferMatrix& m,
                             const std::map<std::string, std::vector<FrdPoint>>& data);

Json state_model_json(const StateModel& s);

}  // namespace fralab
