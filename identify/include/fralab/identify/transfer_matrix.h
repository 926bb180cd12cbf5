// The transfer matrix of an operating point (the report's Figures 1-3): each measured path's fitted
// tf in a table of outputs (rows) by inputs (columns), and the common poles across it.
//
// Common poles (Section I, "Form of the model"): poles of all paths are clustered (real with real,
// pairs with pairs; a root joins a cluster whose mean lies within `rel_tol` relative distance).
// A cluster present in every fitted path into one output is that output's (a sensor, scope
// "output"); in every fitted path from one input, that input's (an actuator, scope "input"); in
// every path, a plant state ("plant"); otherwise "path". The state count of the operating point is
// the number of distinct clusters (each counted once), as the report's recipe counts states.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fralab/identify/pole_set_fit.h"
#include "fralab/identify/tfns.h"

namespace fralab {

struct MatrixEntry {
  std::string input, output;  // response output / input
  FitResult fit;
};

struct PoleCluster {
  Root mean;                       // mean location (real) or (wn, zeta)
  std::vector<std::string> pairs;  // "input:output" members
  std::string scope;               // "plant", "output", "input", "path"
  std::string where;               // the output or input name for those scopes
};

struct TransferMatrix {
  std::vector<std::string> inputs, outputs;
  std::map<std::pair<std::string, std::string>, FitResult> fits;  // (output, input)
  std::vector<PoleCluster> clusters;
  int state_count = 0;
  // The clusters are one pole set's (common_pole_matrix): a path's states are the clusters it is
  // a member of, not those nearest its own fit's poles (state_model.h, 1.).
  bool from_pole_set = false;
};

/// One root as the report writes its factor: [s/a + 1] a stable real root (-a), [1 - s/a] a
/// right-half-plane one (a), [(s/w)^2 + 2(z)s/w + 1] a pair (w rad/s, damping z).
std::string factor_text(const Root& r);

/// Human form of a tf in the report's notation: 2.86 [1 - s/192] / ([s/2.86 + 1][s/76.7 + 1])
/// e^(-0.011 s).
std::string tf_to_text(const Tf& tf);

TransferMatrix build_transfer_matrix(const std::vector<MatrixEntry>& entries, double rel_tol = 0.1);

/// The matrix's states from one pole set (pole_set_fit.h) fitted over every path whose fit has a
/// model, each curve on its own grid with its fit's delay removed, instead of each path's poles
/// clustered after the fact. `data`: the measured curves keyed "input:output". The clusters are
/// the set's poles; a path is a member of a pole when the pole's peak term |r| / |Re p| reaches 1 %
/// of the path's rms |G|; scopes as build_transfer_matrix's. Weights: 1 / sigma^2 on a curve with
/// sigma, else 1 / (noise_rel |G|)^2 with the path's fit's estimated relative noise (1 % when it
/// has none). The fits stay each path's own.
struct CommonPoleMatrix {
  TransferMatrix matrix;           // from_pole_set; clusters from the pole set
  PoleSetFit fit;                  // its curves in `paths`' order
  std::vector<std::string> paths;  // "input:output"
};
CommonPoleMatrix common_pole_matrix(const TransferMatrix& m,
                                    const std::map<std::string, std::vector<FrdPoint>>& data,
                                    const PoleSetFitOptions& o = {});
Json transfer_matrix_json(const TransferMatrix& m);
std::string transfer_matrix_markdown(const TransferMatrix& m, const std::string& title);

}  // namespace fralab
