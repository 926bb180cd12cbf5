// Internal to the diagnosis: one measured pair against the simulation (the residual's data), a
// fitted cause candidate, and the numerics every cause's fit uses. Frequencies rad/s, s = jw.
#pragma once

#include <complex>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "fralab/diagnose/diagnose.h"

namespace fralab::diag {

using C = std::complex<double>;

/// One pair's usable points against the current model. The model is sim * factor * F for a
/// candidate factor F; chi2 weighs each complex point by 1/sigma_eff^2.
struct PairFit {
  std::string pair, input, output;          // output "" for actuator pairs u_X:X
  std::vector<double> w, amp, h3;           // rad/s; excitation amplitude; 3rd harmonic of E2
  std::vector<double> line_amp, nl;         // a multisine's: the line's command amplitude; nl_rel
  std::vector<int> realisations;            // a multisine's realisations averaged (0: one)
  const MultisineExcitation* ms = nullptr;  // the input's multisine, when this pair is one's
  std::vector<C> meas, sim;                 // sim: the simulation (unchanged by findings)
  std::vector<double> sig;                  // sigma_eff
  std::vector<C> factor;                    // product of accepted cause factors so far
};

/// A fitted candidate: the cause, its parameters (docs/formats.md §6 names), its factor F at each
/// point of the pair, chi2 with F applied, k free parameters, and `detail` (the resonance's
/// "peak"/"notch", or a nonlinearity's explanation).
struct Cause {
  CauseKind cause = CauseKind::kGainMismatch;
  Parameters params;
  std::vector<C> F;
  double chi2 = INFINITY;
  int k = 1;
  std::string detail;
};

/// A point says something about the model only when it is measured to better than max_rel_sigma
/// (an actuator inside its backlash, or a response down in the noise, is not).
bool usable(const FrdPoint& p, const DiagnoseOptions& o);

/// Each input's multisine as the diagnosis takes it: from its actuator curve u_X:X, else from the
/// first other curve of the input (in `data`'s order) that is a multisine's (multisine_excitation);
/// `curve` picks each pair's measurement (its fitting one, its validation, a level's; null: none).
std::map<std::string, MultisineExcitation> input_multisines(
    const std::vector<MeasuredPair>& data,
    const std::function<const Frd*(const MeasuredPair&)>& curve);

/// Appends a usable measured point and the simulation's response `sim` there: sigma_eff =
/// hypot(sigma, (sigma_floor + aliasing_floor (w h)^2) |G|), factor 1.
void add_point(PairFit& p, const FrdPoint& pt, C sim, const DiagnoseOptions& o);

/// sum_i |meas_i - sim_i factor_i F_i|^2 / sig_i^2.
double chi2(const PairFit& p, const std::vector<C>& F);

/// f(j w_i) at every w_i.
std::vector<C> factor_of(const std::vector<double>& w, const std::function<C(C)>& f);

/// 1-D minimisation on [lo, hi]: a grid of `grid` + 1 points, then Brent's method around the best.
double minimise_1d(const std::function<double(double)>& f, double lo, double hi, int grid = 60);

/// `v` with `prec` significant digits.
std::string fmt(double v, int prec = 3);

}  // namespace fralab::diag
