// Transfer-function identification from frequency-response data: the TFNS program of the report's
// Appendix B (Suzuki's method, a Sanathanan-Koerner iteration), made numerically sound, and carried
// on to an output-error optimum. The method, each step's thresholds and why:
// docs/method/identifier.md.
//
// Model (docs/formats.md §1): G_a(s) = N(s)/D(s) e^{-s tau}, factored into real roots and pairs,
// stable poles. Steps: frequencies scaled by ws = sqrt(w_min w_max); SK at orders (n, m) in a basis
// orthonormal on the data (B-5, B-8, B-9), restarted from vector fitting's poles when not adequate;
// roots from the basis' confederate matrix; the delay searched when the best delay-free fit is
// inadequate or has right-half-plane zeros; each candidate refined to the output-error optimum of
// sum_i W_i |G_i - G_a(j w_i)|^2 (MINPACK's Levenberg-Marquardt); the order raised until adequate,
// chosen among adequate candidates by chi^2 + ln(2N) p; with sigma and no order adequate, sigma
// scaled by the best chi^2/dof (the status says so), and a pole set of up to max_poles tried;
// then pruning of near-cancelling and unresolved roots, and a right-half-plane zero above the band
// replaced by its lag unless the data prefer it.
// Adequate: with sigma, chi^2 / (N - p/2) <= 1 + 3 / sqrt(N); without, the TFNS real error
// sum W |G - G_a|^2 / sum W |G|^2 <= c_n. Weights W_i: 1 / sigma_i^2 when the data carry sigma
// (or the noise is estimated), else 1 / |G_i|^2. Units: w rad/s, tau seconds, phases radians
// inside, degrees in files.
#pragma once

#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/tf.h"

namespace fralab {

struct FitOptions {
  int den_order_start = 1;  // TFNS "C" card: denominator starting order
  int num_order_start = 0;  // numerator starting order (<= den)
  int max_den_order = 10;
  double c_phi = 0.01;       // equation error tolerance (B-9)
  double c_n = 0.01;         // real error tolerance (without sigma, when estimate_noise is false)
  int max_iterations = 100;  // SK iterations per order
  enum class Delay { kNone, kAuto, kFixed } delay = Delay::kAuto;
  double delay_s = 0.0;      // kFixed: subtracted (TFNS sense switch 2); kAuto: ignored
  double max_delay_s = 0.2;  // kAuto: the delay is searched and fitted in [0, max_delay_s], never
                             // outside
  // Without sigma: the stop rule is the reduced chi^2 against sigma_i = s |G_i|, s the
  // data's relative noise level: `tolerance` when > 0, else estimated from the data (the residual
  // of deliberately over-fitted models, delay removed: of the over-fit as a model of roots, or of
  // its polynomials when rooting a degenerate over-fit lost more than 100x), never below
  // noise_floor. Estimated, the noise may have an absolute part: sigma_i^2 = a^2 |G_i|^2 + b^2
  // when the over-fit's residuals support it (noise_model.h: a measured path's output noise), and
  // then, as with a sigma given, a path with fewer than 3 points above 0.3 sigma is no_response.
  // false: TFNS's E_N <= c_n.
  bool estimate_noise = true;
  double tolerance = 0;       // assumed relative noise (rms |G - G_a| / |G| accepted); 0: estimate
  double noise_floor = 1e-9;  // lowest estimated relative noise (noise-free data fit to ~this)
  int min_num_order = 0;      // numerator orders tried at each n: n down to max(this, 0)
  bool refine = true;         // output-error refinement
  bool use_sigma = true;      // weight by 1/sigma^2 when present
  // When the order search runs up to max_den_order without an adequate order (data of more modes
  // than that), a pole set of up to this many poles is fitted too (pole_set_fit.h: vector fitting
  // with poles added and skimmed) and kept when its criterion (step 5) is lower; 0: never.
  int max_poles = 40;
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct RootInfo {
  double real = 0, imag = 0;  // s-plane location (upper half plane for pairs), rad/s
  double wn = 0, zeta = 0;    // frequency and damping (pairs); wn = |real| for real roots
  bool pair = false;
  // Standard deviation of the location, relative to |root| (< 0: unknown): from the refinement's
  // covariance; for a pair hypot(sigma_ln_wn, min(sigma_zeta / sqrt(1 - zeta^2),
  // sqrt(2 sigma_zeta))), the second term the split into two reals near zeta = 1.
  double rel_sigma = -1;
};

/// A pole pair and zero pair (or real pole and RHP real zero) mirrored about the imaginary axis:
/// the signature of a Pade approximation of a delay (Section III).
struct PadeSet {
  Root zero, pole;
  double delay_s = 0;  // its low-frequency group delay
};

struct FitResult {
  // kConverged: the model is adequate (consistent with the noise), or chosen by the criterion over
  // an adequate one. kMaxOrderReached: no order is adequate and the search tried up to the highest
  // denominator order allowed (max_den_order, or the number of points less one). kNotAdequate: no
  // order is adequate and the search stopped below that maximum (the error stopped improving, or a
  // refinement of given orders: refine_tf); the message says why. kNoResponse: the data carry
  // sigma and fewer than 3 points rise above it (sigma <= 0.3 |G|): the path is zero within the
  // measurement (the report's matrix shows such paths as 0). The best model is kept with
  // kMaxOrderReached and kNotAdequate alike (has_model()).
  enum class Status {
    kConverged,
    kMaxOrderReached,
    kFailed,
    kNoResponse,
    kNotAdequate
  } status = Status::kFailed;
  /// A model was fitted: converged, max_order_reached or not_adequate.
  bool has_model() const {
    return status == Status::kConverged || status == Status::kMaxOrderReached ||
           status == Status::kNotAdequate;
  }
  std::string message;
  Tf tf;
  int num_order = 0, den_order = 0;
  int iterations = 0;        // SK iterations at the final order
  double e_phi = 0;          // final equation error
  double e_n = 0;            // TFNS real error (normalised, weights W)
  double chi2_per_dof = -1;  // with sigma
  double rms_rel_error = 0;  // sqrt(mean |G - G_a|^2 / |G|^2)
  double max_rel_error = 0;
  int n_points = 0;
  int unstable_reflected = 0;
  std::vector<PadeSet> pade;
  double pade_delay_s = 0;                     // sum of the Pade sets' delays
  std::vector<RootInfo> zero_info, pole_info;  // with rel_sigma from the fit's covariance
  double gain_rel_sigma = -1;                  // relative standard deviation of the DC gain
  double delay_sigma_s = -1;                   // standard deviation of a fitted delay
  double noise_rel = -1;  // without sigma: the relative noise level the stop rule used (< 0: c_n)
  // Without sigma, when the data's noise has an absolute part (noise_model.h): b of sigma_i^2 =
  // noise_rel^2 |G_i|^2 + b^2, in the ratio's units (< 0: relative only).
  double noise_abs = -1;
  // With sigma and no order adequate: the factor sigma was scaled by to choose the order (sqrt of
  // the lowest chi^2/dof reached); 1: not scaled. chi2_per_dof stays against the sigma given.
  double sigma_scale = 1;
  std::string status_str() const;
};

/// Identifies a tf from valid points of `data` (invalid points are skipped). Needs >= 3 points.
FitResult fit_tf(const std::vector<FrdPoint>& data, const FitOptions& opt);

/// Output-error refinement (weighted Levenberg-Marquardt, as fit_tf's last stage) of `start` on the
/// valid points of `data`: its orders and root kinds are kept; the delay is opt.delay_s (kFixed),
/// 0 (kNone) or fitted jointly from start.delay_s (kAuto). Status, figures and sigmas as fit_tf's.
/// (An oracle's fit in the benchmark: the true structure from the true start.)
FitResult refine_tf(const std::vector<FrdPoint>& data, const Tf& start, const FitOptions& opt);

/// Root table of a tf (locations, frequency and damping).
std::vector<RootInfo> root_info(const std::vector<Root>& roots);

/// Pade-like sets among a tf's roots: a zero mirrored onto a pole within `tol` relative distance.
std::vector<PadeSet> find_pade_sets(const Tf& tf, double tol = 0.15);

/// JSON of a fit: the tf (docs/formats.md §1) plus "fit" figures, "roots", "pade".
Json fit_to_json(const FitResult& r, const std::string& pair);

}  // namespace fralab
