// One pole set for one or several frequency responses (each on its own grid), its size found from
// the data: vector fitting (Gustavsen and Semlyen 1999; relaxed, Gustavsen 2006; several responses
// with one pole set as in Deschrijver et al. 2008's fast VF) inside an adding and skimming loop
// (Grivet-Talocia and Gustavsen, "Passive Macromodeling", 2016, sec. 7.4: poles are added where the
// residual stands above the noise, and those whose removal does not raise the error by more than
// their penalty are taken out).
//
// Model of curve c:  G_c(s) = d_c + sum_k r_ck / (s - p_k)  (+ the conjugate term of each complex
// pole), s = j w, w in rad/s; poles p_k shared by every curve, stable (unstable ones reflected),
// each complex pair listed once by its upper-half-plane member; residues per curve (real for a real
// pole), d_c real.
//
// The loop, on weights W_ci (1 / sigma_ci^2; curves of no sigma weighted 1 / |G|^2 by the caller):
// 1. Start: `start_pairs` pairs at frequencies spread linearly over the band (resonant data: a
//    linear spread puts start poles where modes are dense; Gustavsen's advice), real part -1 %.
// 2. `relocations` VF relocations of all poles against all curves (each curve's equations reduced
//    by QR to the rows of the scaling function's unknowns, stacked; the relaxation row).
// 3. Residues and d per curve by weighted least squares; chi^2 = sum_c,i W |e|^2.
// 4. While chi^2 / dof > 1 + 3 / sqrt(dof) (dof = 2 M C - parameters; not adequate) and under
//    max_poles: pairs are added at the largest peaks of the weighted residual (several at once,
//    up to a quarter of the poles so far, each peak at least 5 grid points from the others), with
//    a real part of two local grid spacings; back to 2. The loop stops when two rounds in a row
//    lower the criterion chi^2 + kappa p (kappa = ln(2 M C), the order search's) by less than 1 %.
// 5. Skimming: while some pole's removal (residues refitted) raises chi^2 by less than kappa times
//    the parameters it takes (2 for a pair plus its residues, per curve), the cheapest is removed
//    and the rest relocated.
// 6. Polishing: 3 x `relocations` more relocations of the chosen set; the best by the criterion.
// The best model by the criterion over all rounds is returned.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "fralab/core/tf.h"

namespace fralab {

struct PoleSetFitOptions {
  int max_poles = 40;   // counting each pair as 2
  int start_pairs = 2;  // step 1
  int relocations = 4;  // VF relocations per round (step 2)
  int max_rounds = 30;  // adding rounds (step 4)
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct PoleSetFit {
  enum class Status { kAdequate, kNotAdequate, kFailed } status = Status::kFailed;
  std::string message;
  std::vector<std::complex<double>> poles;                  // rad/s; pairs by their upper member
  std::vector<std::vector<std::complex<double>>> residues;  // [curve][pole]
  std::vector<double> d;                                    // [curve]
  std::vector<double> chi2;                                 // [curve] sum W |e|^2
  double chi2_total = 0, chi2_per_dof = 0;
  int order = 0;  // poles counting each pair as 2
  int rounds = 0, added = 0, skimmed = 0;

  /// G_c(j w) of curve c.
  std::complex<double> at(size_t c, double w) const;
  /// Curve c as a factored transfer function (docs/formats.md §1): the poles, the zeros of
  /// d_c + sum r / (s - p) (the finite generalized eigenvalues of [A b; c d] against
  /// [I 0; 0 0]), the gain G_c(0). Zeros at s = 0 within 1e-12 of the band cannot be written in
  /// that form: they are moved to 1e-9 of the band's lowest frequency.
  Tf to_tf(size_t c) const;
};

/// The pole set of curves g[c][i] at w[c][i] (rad/s, > 0, increasing; each curve on its own grid),
/// weights W[c][i] >= 0. Needs at least 4 points a curve; at most (the smallest curve's points - 2)
/// poles. Status kFailed with a message naming the curve for a bad grid or mismatched sizes.
PoleSetFit fit_pole_set(const std::vector<std::vector<double>>& w,
                        const std::vector<std::vector<std::complex<double>>>& g,
                        const std::vector<std::vector<double>>& W, const PoleSetFitOptions& o = {});

/// The same with one grid w shared by every curve.
PoleSetFit fit_pole_set(const std::vector<double>& w,
                        const std::vector<std::vector<std::complex<double>>>& g,
                        const std::vector<std::vector<double>>& W, const PoleSetFitOptions& o = {});

/// Vector fitting at one fixed order, no adding or skimming: `pairs` pairs spread linearly over the
/// band (step 1), relocated `relocations` times against every curve on the shared grid w (rad/s).
/// The poles in rad/s, stable, pairs by their upper member (a pair may split into two real
/// poles); empty for a bad grid or more poles than the points allow (2 pairs + 2 > points).
std::vector<std::complex<double>> relocated_poles(
    const std::vector<double>& w, const std::vector<std::vector<std::complex<double>>>& g,
    const std::vector<std::vector<double>>& W, int pairs, int relocations);

}  // namespace fralab
