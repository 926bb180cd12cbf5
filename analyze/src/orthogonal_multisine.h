// The orthogonal multisine's analysis for one pair E1:E2 (pair_analyzer.h states its equations):
// each experiment's spectra at the lines, kept until its realisation's n_u experiments are in,
// then the responses to each input solved per line, h = X U^{-1}.
#pragma once

#include <complex>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "fralab/core/block.h"
#include "fralab/core/frd.h"

namespace fralab::analyze_detail {

// One experiment's spectra at the lines, per period (M periods, L lines).
struct OrthogonalExperiment {
  bool valid = true;
  std::string note;
  std::vector<std::vector<std::complex<double>>> x1, x2;  // [line][period]
  // [line][neighbour][period]: the same at the nearest non-excited line each side (noise pooled
  // from them)
  std::vector<std::vector<std::vector<std::complex<double>>>> nb1, nb2;
  std::vector<std::vector<std::complex<double>>> u;    // [line][input q]: period-mean command
  std::vector<std::vector<std::complex<double>>> pos;  // [line][input q]: the same of its position
  // [line][input q]: the variance of that period mean (the position's noise, pooled over the
  // line and its nearest non-excited lines, as sigma pools the pair's channels)
  std::vector<std::vector<double>> pos_var;
  std::vector<double> pos_nl;  // [input q]: median over lines of its position's distortion
  std::vector<double> nl;      // [line]: E2 on the nearest unexcited lines / |X2|
};

/// A channel's samples over the window, from its first; nullptr where the tape has no such
/// channel over the whole window or it holds a NaN there.
using WindowChannel = std::function<const double*(const std::string& channel)>;

/// The experiment of window st (its inputs ins, indices into st.inputs): E1's samples a and E2's
/// b from the window's first, the commands u_X and positions X of the inputs from `channel`.
/// Invalid, with a note naming it, without periods or with a command or position missing.
OrthogonalExperiment orthogonal_experiment(const StatusEvent& st, const std::vector<int>& ins,
                                           const double* a, const double* b,
                                           const WindowChannel& channel);

/// The realisations of one pair's orthogonal multisines, each until its experiments are in.
class OrthogonalRealisations {
 public:
  /// e1, e2: the pair's channels; an input whose position distorts above distortion_threshold
  /// enters a pair X:O's input matrix by its position (AnalyzerOptions).
  OrthogonalRealisations(std::string e1, std::string e2, double distortion_threshold);

  /// Experiment e = st.step % n_u of realisation r = st.step / n_u (n_u = ins.size()); returns
  /// the realisation's points once its n_u experiments are in, nothing before. An experiment
  /// whose status states another design than the realisation's first is invalid.
  std::vector<FrdPoint> add(const StatusEvent& st, const std::vector<int>& ins,
                            OrthogonalExperiment ex);

  /// One invalid point for each realisation whose experiments never all arrived (their status
  /// lost), naming those missing; the realisations are then forgotten.
  std::vector<FrdPoint> incomplete();

 private:
  struct Group {
    StatusEvent st;                                   // its first experiment's status
    std::vector<int> ins;                             // its inputs
    std::map<int, OrthogonalExperiment> experiments;  // by experiment e
  };
  std::vector<FrdPoint> solve(int r, const Group& grp) const;
  std::vector<int> wanted_inputs(const Group& grp) const;
  std::vector<bool> inputs_by_position(const Group& grp) const;

  std::string e1_, e2_;
  double distortion_threshold_;
  std::map<int, Group> groups_;  // by realisation
};

}  // namespace fralab::analyze_detail
