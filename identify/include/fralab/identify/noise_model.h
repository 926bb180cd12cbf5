// The noise of frequency-response data that carry no sigma: the level fit_tf's order
// rule judges candidates against when the analyser's sigma is not there.
//
// Model: the complex error of point i is circular Gaussian with variance
//   v_i = a^2 |G_i|^2 + b^2,
// a relative part a (noise proportional to the response: a noisy input's, or the random
// benchmark's draw) and an absolute part b in the ratio's own units (a measured path's output
// noise over the input's amplitude: the J85 lab's Wf:N has sigma / |G| from 0.13 % at 0.25 rad/s
// to 150 % at 310 rad/s while |G| falls 700x, sigma itself within 10x over the band).
//
// Estimated from the residuals e_i of a model deliberately fitted above the data's order (fit_tf's
// over-fits), by maximum likelihood with each point's residual given the variance the fit leaves
// it. A weighted least-squares fit (weights W_i on |e_i|^2, tangent space A at the fit, real and
// imaginary parts as rows) leaves e = (I - H) n, H = A (A^T W A)^-1 A^T W, so
//   E|e_i|^2 = a^2 r_i + b^2 q_i,   r_i, q_i = (1 / W_i) sum_{j of i} sum_l P_jl^2 W_l c_l / 2,
// P = I - Q Q^T (Q an orthonormal basis of W^1/2 A), c_l = |G_l|^2 for r, 1 for q: exact for any
// weights to first order (with W_i = 1 / v_i, r_i a^2 + q_i b^2 = v_i (1 - h_i / 2), h_i point i's
// leverage; counted as whole points, the level of a flat fit of additive noise came out 0.87 of
// the level drawn in noise_model_test, about 1 - p / 2N). A fit far from linear breaks it: weighted
// relatively, an over-fit of additive noise fits the points where |G| is small closely and the
// others carry the error of a poorly weighted fit (estimates 0.35-1.3x the level on such draws);
// fit_tf therefore judges each hypothesis with its own over-fit (restricted_likelihood). The
// working negative log-likelihood (per-point constants dropped; the residuals' correlation
// ignored, which keeps its estimating equations unbiased) is
//   L(a, b) = sum_i [ |e_i|^2 / vhat_i + ln vhat_i ],   vhat_i = a^2 r_i + b^2 q_i,
// profiled over the scale (vhat = s u: s = mean_i |e_i|^2 / u_i) and minimised over the shape
// u_i = cos(phi) r_i / m + sin(phi) q_i, m the geometric mean of |G_i|^2, phi in [0, pi/2] (0:
// relative only, pi/2: absolute only): a grid over tan(phi) = 10^x, then Brent's method. Points the
// fit left less than 0.2 of their degrees of freedom are not counted. The relative model alone
// (phi = 0) over whole points is a^2 = mean_i |e_i|^2 / |G_i|^2 (fit_tf keeps its own relative
// level, sse / (N - p / 2) of the over-fits).
// Units: w rad/s; a dimensionless; b and |G| in the ratio's units.
#pragma once

#include <vector>

#include "fralab/core/tf.h"

namespace fralab {

struct NoiseModel {
  double rel = 0;  // a: standard deviation of the complex error relative to |G|
  double abs = 0;  // b: standard deviation of the complex error, in the ratio's units
  /// sqrt(a^2 mag^2 + b^2) (exactly a mag when b = 0).
  double sigma(double mag) const;
};

struct NoiseFitOptions {
  // The log-likelihood gain (L units: half the likelihood-ratio statistic) the model with an
  // absolute part needs over the relative one to be chosen. 5: a likelihood-ratio statistic of 10,
  // p ~ 1e-3 for a chi^2 with one degree of freedom (independent residuals of relative noise read
  // as additive in about 1 in 1000 estimates; an over-fit's residuals are not independent, and
  // fit_tf uses this test only to propose the mixed shape, which restricted_likelihood then judges
  // with the same margin, 2 x evidence in -2 l).
  double evidence = 5;
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct NoiseFit {
  bool ok = false;      // false: fewer than 2 points left with a residual variance, or none finite
  NoiseModel model;     // the chosen one: `mixed` when absolute_part, else `relative`
  NoiseModel relative;  // the relative model alone (b = 0) at its optimum
  NoiseModel mixed;     // both parts at their optimum (b may be 0, a may be 0)
  double l_relative = 0, l_mixed = 0;  // L at each optimum
  bool absolute_part = false;          // l_relative - l_mixed >= evidence
};

/// What a weighted least-squares fit leaves of each point's noise: E|e_i|^2 = a^2 rel[i] + b^2
/// abs[i] (see above), and dof[i] = 1 - h_i / 2 in [0, 1] (sum: N - rank / 2).
struct ResidualVariance {
  std::vector<double> rel, abs, dof;
};

/// For the fit `model` (its delay fixed) at w_i (rad/s) with weights W_i (> 0) on |e_i|^2: the
/// tangent space's columns G(jw_i) and, per root with unity-DC-gain factor F, G / F (a pair also
/// G (jw / wn) / F), times sqrt(W_i); their rank by a column-pivoted QR with threshold 1e-10 (a
/// degenerate over-fit's near-cancelling couples span no more than one of them). mag2[i] = |G_i|^2
/// of the data (the relative part's scale).
ResidualVariance residual_variance(const std::vector<double>& w, const std::vector<double>& W,
                                   const std::vector<double>& mag2, const Tf& model);

/// Maximum-likelihood noise model of residuals e2[i] = |e_i|^2 with their variance factors (one
/// length); mag2[i] = |G_i|^2 (> 0) sets the geometric-mean scale of the relative part.
NoiseFit fit_noise_model(const std::vector<double>& e2, const std::vector<double>& mag2,
                         const ResidualVariance& rv, const NoiseFitOptions& o = {});

/// Which noise shape the data support, between hypotheses each with its own least-squares fit: the
/// restricted (REML) likelihood of the data under noise variances v_i = s u_i, whose fit `model`
/// (its delay fixed) was weighted by 1 / u_i (its GLS fit under that shape), residuals e2[i] =
/// |e_i|^2, the scale profiled (s = sum_i e2_i / u_i / (N - r / 2)):
///   -2 l = sum_i [2 ln(s u_i) + 2 |e_i|^2 / (s u_i)] + ln det(A^T V^-1 A)   (+ a constant),
/// V the real rows' variances (s u_i / 2 each), A the tangent space of residual_variance, r its
/// rank. The smaller -2 l is the better supported; the log-determinant charges a shape for the
/// points its own fit absorbs (a relative shape's small variances where |G| is small are the points
/// a relatively weighted fit fits closely). Units: w rad/s.
struct Restricted {
  double m2l = INFINITY;  // -2 l; infinite: not computable (no finite fit, fewer points than r / 2)
  double scale = 0;       // s
  int rank = 0;
};
Restricted restricted_likelihood(const std::vector<double>& w, const std::vector<double>& e2,
                                 const std::vector<double>& u, const Tf& model);

}  // namespace fralab
