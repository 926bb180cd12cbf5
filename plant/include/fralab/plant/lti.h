// Exact sampled simulation of one SISO transfer function (docs/formats.md §1) driven by a sampled
// input.
//
// The input samples u[k] (period h seconds) are joined by straight lines (first-order hold): the
// continuous system sees the piecewise-linear u(t), and the output samples y[k] are the exact
// samples of the continuous response to it, y[k] = y(k h). A delay d = (m + f) h is exact: the
// system is driven by u(t - d), piecewise linear with knots at (j + m + f) h, and a step that holds
// a knot is integrated in two exact sub-steps (f h, then (1 - f) h).
//
// Realisation: modal (diagonal complex modes, O(n) per sample) when the poles are distinct;
// otherwise a cascade of first/second-order sections in state space, discretised through the
// matrix exponential of the augmented FOH matrix. Both are exact for a piecewise-linear input; no
// high-order polynomials are formed.
//
// Consequence for frequency response: for u[k] = sin(w k h) the steady-state output is the
// sinusoid with phasor  sum_m G(j(w + m ws)) F(w + m ws),  ws = 2 pi / h, F(v) = sinc^2(v h / 2):
// the m = 0 term is G(jw) times the hold's real factor F(w) ~ 1 - (w h)^2 / 12; the images m != 0
// alias back and are small when G rolls off (F(ws - w) ~ (w h / 2 pi)^2). Two channels
// driven by the same samples share F(w), so their ratio is G2/G1 up to the images only.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <optional>
#include <vector>

#include "fralab/core/tf.h"

namespace fralab {

/// The exact steady-state response of FohLti(tf, 1/fs) to a sampled sinusoid of w rad/s: the FOH
/// image sum above (terms |m| <= 4000; the truncated tail is below 1e-7 relative for a proper tf).
/// Equals tf.at(w) * sinc^2(w / (2 fs)) plus the aliased images. Delays included.
std::complex<double> foh_sampled_response(const Tf& tf, double w, double fs);

class FohLti {
 public:
  enum class Form { kModal, kCascade };

  /// Precondition: tf proper (num order <= den order), poles in the open left half plane,
  /// sample_period_s > 0. Violations throw InputError naming the tf. `force` chooses the form
  /// (tests compare both); by default modal unless two poles lie within 1e-3 relative distance.
  explicit FohLti(const Tf& tf, double sample_period_s, std::optional<Form> force = std::nullopt);

  /// Feeds u[k] (deviation from the operating point) and returns y[k].
  double step(double u);
  /// Back to rest: zero state, zero input history.
  void reset();
  Form form() const { return form_; }
  int order() const { return order_; }

 private:
  struct ModalDisc {
    std::vector<std::complex<double>> phi, g0, g1;
  };
  struct DenseDisc {
    Eigen::MatrixXd phi;
    Eigen::VectorXd g0, g1;
  };
  void build_modal(const Tf& tf);
  void build_cascade(const Tf& tf);
  ModalDisc modal_disc(double h) const;
  DenseDisc dense_disc(double h) const;
  void advance(int which, double v0, double v1);
  double output(double v) const;

  Form form_ = Form::kModal;
  int order_ = 0;
  double h_ = 0.0;
  double d_ = 0.0;  // feedthrough
  // modal
  std::vector<std::complex<double>> p_, c_, z_;
  ModalDisc md_[3];  // full step, first sub-step (f h), second sub-step ((1 - f) h)
  // cascade
  Eigen::MatrixXd a_;
  Eigen::VectorXd b_, x_;
  Eigen::RowVectorXd cr_;
  DenseDisc dd_[3];
  // delay
  int m_ = 0;
  double f_ = 0.0;
  std::vector<double> hist_;  // ring: hist_[(pos_ - j) mod size] = u[k - j]
  size_t pos_ = 0;
  double v_prev_ = 0.0;
};

}  // namespace fralab
