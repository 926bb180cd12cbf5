// Transfer-function identification from frequency-response data: the TFNS program of the report's
// Appendix B (Suzuki's method, a Sanathanan-Koerner iteration), made numerically sound, and carried
// on to an output-error optimum.
//
// Model (docs/formats.md §1): G_a(s) = N(s)/D(s) e^{-s tau}, factored into real roots and pairs.
//
// 1. Frequency scaling (TFNS's scale factor): s' = s / ws, ws = sqrt(w_min w_max), centring the
//    logarithms of the data's frequencies around zero.
// 2. SK iteration at orders (n, m): minimise E_phi = sum_i phi_i |D(s_i) G_i - N(s_i)|^2 (B-5) with
//    phi_i = W_i / |D^{(k-1)}(s_i)|^2 (B-8), until the equation error
//    E_phi' = mean_i |1 - D^{(k)}(s_i) / D^{(k-1)}(s_i)| (B-9, D normalised to D(0) = 1) is <=
//    c_phi. The polynomials are expanded in a basis orthonormal on the data (Arnoldi on the points
//    +-j w_i with weights phi_i, so coefficients stay real); N is eliminated by projecting onto
//    those orthonormal columns and D is the smallest right singular vector of the QR factor of what
//    remains (||d|| = 1): never normal equations in raw powers of s. The iterate with the lowest
//    real error is kept; an iteration that has not lowered it for 3 iterations stops (SK is a
//    fixed point, not a descent: with noise or a wrong delay it can oscillate).
//    When SK's fit at (n, m) is not adequate, SK is run again with its first weights from vector
//    fitting's n poles (vector_fitting.h); the better of the two is refined first, the other too
//    when that one does not become adequate. Below the first adequate order this restart is made
//    at m = n, and at lower m only when it won at a higher m of that n.
// 3. Roots: eigenvalues of the basis' confederate matrix; unstable poles are reflected into the
//    left half plane.
// 4. Delay (auto): searched when the best delay-free fit is inadequate or has right-half-plane
//    zeros (with noise, a rational imitating a delay need not show clean mirrored sets); a delayed
//    model wins only with no more parameters and a lower criterion (5). The search: a grid over
//    [0, top] scored by SK at (2, 2), the phase step at w_max below 3 rad, then Brent's method
//    around its best; per order, the delay starts are the best separated points of an SK (n, n)
//    grid +-10 windows (on multiples of the window) around that best, and around the grid's
//    runner-up local minimum when it is within 10 % of the best (a high relative degree makes the
//    (2, 2) grid nearly flat).
//    Output-error refinement (MINPACK's Levenberg-Marquardt, steps from the normal equations by
//    Cholesky, a converged optimum polished by one QR-solved Gauss-Newton step) of sum_i W_i |G_i -
//    G_a(j w_i)|^2 over the factored parameters (real poles -exp(t), pairs wn = exp(a), zeta =
//    exp(b): stable by construction; real roots of one sign are refined in pairs, zeta >= 1 being
//    two reals, so they can become a resonance) and, with delay auto, tau jointly. Every candidate
//    short of hopeless (chi^2/dof < 30) is refined, screened with at most 60 residual evaluations;
//    candidates compared across orders, and the chosen fit, are refined to convergence. A
//    refinement also stops when the objective has fallen by less than 0.1 chi^2 units (without
//    sigma: 1e-4 of itself) over ten steps. A candidate that fits but is refused for a cancelling
//    dipole (a zero and a pole of one kind within 1e-3) has the couple removed and the rest
//    refined.
// 5. Order: starting at (n0, m0), raised until the fit is adequate: with sigma, the reduced
//    chi^2 = sum |G_i - G_a|^2 / sigma_i^2 / (N - p/2) <= 1 + 3 / sqrt(N) (consistent with the
//    measured noise); without sigma, the TFNS real error E_N = sum W |G - G_a|^2 / sum W |G|^2 <=
//    c_n. At each n, numerator orders n down to min_num_order are tried, until one misses clearly
//    (10x the threshold and 10x the order's best error) while fitting less than 10x worse than the
//    previous order's candidates it contains (n - 1, k <= m): worse, it is a failed fit. Among
//    adequate candidates the lowest criterion chi^2 + ln(2N) p wins (twice BIC's penalty: an added
//    root's location is searched), and the order is raised past the first adequate one while the
//    criterion improves; without sigma (c_n rule) the fewest parameters win. Above order 3,
//    raising stops when two successive orders improve the error by less than 5 %. With sigma
//    given, past an adequate fit (n, m), when every start of (n + 1, m) or (n + 1, m + 1) fits
//    worse than it, that order also starts nested in it: a real pole at -100 w_max, or a real
//    pole-zero couple at the frequency of its largest weighted residual. The choice is then that
//    of the criterion over every candidate tried with fewer parameters that passes the test at
//    4 sigma, chi^2/dof <= 1 + 4 / sqrt(N) (the true orders miss 3 sigma by chance in ~0.5 % of
//    fits): such a fit is kConverged, its message says it was chosen by the criterion.
// 6. With sigma and no order adequate (the data scatter more than their sigma says), steps 2-5 run
//    again with sigma scaled by sqrt of the lowest chi^2/dof any physical candidate reached; the
//    status stays not adequate (kMaxOrderReached when the search went up to the maximum order,
//    else kNotAdequate), chi2_per_dof against the sigma given, sigma_scale the scale.
// 6b. With sigma (given or estimated) and the search run up to max_den_order without an adequate
//    order, a pole set of up to max_poles poles (pole_set_fit.h) replaces the fit when its
//    criterion chi^2 + ln(2N) p is lower (the message says so): many light modes, which the order
//    search's capped sweep cannot hold.
// 7. Pruning of the chosen fit: each zero with the nearest pole of its kind closer than half the
//    pole's modulus, and each root whose relative sigma is >= 0.5, is removed in turn and the rest
//    refined; the best (adequate first, then the criterion of 5) replaces the fit while better,
//    never below min_num_order / den_order_start nor to more zeros than poles.
// 8. A real right-half-plane zero above the band (z > w_max) is the lag 1 / (1 + s/z) there to
//    first order (the same phase, magnitudes (w/z)^2 / 2 apart): it is replaced by that pole and
//    the rest refined, and kept only when its criterion (5) is lower than the lag's by 1 or more
//    (a likelihood ratio of e; with a sigma given or estimated). The message says so.
// Weights W_i: 1 / sigma_i^2 when the data carry sigma (or when the noise is estimated: sigma_i
// from the estimated level, FitOptions::estimate_noise), else 1 / |G_i|^2 (relative error, uniform
// on the log-frequency axis: TFNS's delta-w weighting of absolute error is replaced). Units: w
// rad/s, tau seconds, phases radians inside, degrees in files.
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
