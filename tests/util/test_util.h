// Shared generators and checks for fralab's tests: known-answer signals, an independent
// least-squares sinusoid fit (deliberately not the analyser's code), and model fixtures.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <string>
#include <vector>

#include "fralab/acquire/acquisition.h"
#include "fralab/acquire/campaign.h"
#include "fralab/core/block.h"
#include "fralab/core/frd.h"
#include "fralab/plant/model.h"

namespace fralab::testing {

/// Path of a file in the source tree (models/..., tests/data/...).
std::string source_path(const std::string& rel);

/// Least-squares fit of x[k] ~ c + a sin(w t_k) + b cos(w t_k), t_k = (start + k) h, over the
/// samples [start, start + n); returns the phasor a + j b (so x ~ Im(phasor e^{j w t}) ... i.e.
/// amplitude |p|, phase arg(p) relative to sin(w t)).
std::complex<double> sine_phasor(const std::vector<double>& x, double w, double h, size_t start,
                                 size_t n);

/// A one-input, one-output model with the given tfs, for tests. Output "y", input "u".
Model siso_model(const Tf& path, const Tf* actuator = nullptr, const Tf* sensor = nullptr,
                 double noise_rms = 0.0);

/// A lab run without LCM: the same library code as fralab-acquire (make_campaign, command_block)
/// and fralab-plant (LockstepPlant), producing the tape's records in order. `so` gives the band,
/// points per decade, cycles, integration time, sample rate and settling time constant;
/// `excitation` "stepped", "sweep", "multisine" or "multisine:zippered" (the multisine's design).
struct TapeRun {
  std::vector<StatusEvent> events;
  std::vector<Block> blocks;           // tape blocks: u_<inputs>, positions, outputs
  std::vector<AdaptiveStep> adaptive;  // an adaptive stepped sine's steps
};
TapeRun simulate_tape(const Model& m, const std::vector<std::string>& excite,
                      const SteppedSineOptions& so, bool noise, uint64_t seed, int block = 100,
                      double amplitude_pct = 2.0, const std::string& excitation = "stepped");
/// A multisine of `realisations` random-phase realisations of 2 periods each (the orthogonal
/// design over the excited inputs) on `band` ("LO:HI" Hz), as fralab-acquire's options.
AcquireOptions random_phase_multisine(const std::string& band, int points_per_decade,
                                      double amplitude_pct, int realisations);
/// The auto campaign's first run on a machine (random_machine.h): an orthogonal multisine over
/// 0.1-20 Hz, 5 lines a decade, two measured periods.
AcquireOptions lab_multisine();
/// The same with the acquisition's options as they are (realisations, phases, design, ...); an
/// adaptive stepped sine (o.adaptive) decides on the tape as fralab-acquire does.
TapeRun simulate_campaign(const Model& m, const AcquireOptions& o, bool noise, uint64_t seed);
/// Each pair's curve from a run: a pair analyser fed the run's events, then its blocks in order.
std::vector<Frd> analyse_run(const TapeRun& r, const std::vector<std::string>& pairs);

/// Frequency-response points of `tf` at `per_decade` log-spaced frequencies over [f_lo, f_hi] Hz,
/// with complex Gaussian noise of standard deviation rel_noise * |G| (sigma set accordingly; 0:
/// noise-free, sigma unset).
std::vector<FrdPoint> tf_points(const Tf& tf, double f_lo, double f_hi, int per_decade,
                                double rel_noise, uint64_t seed);

/// Largest relative distance |r_fit - r_true| / |r_true| from each true root (inside
/// [w_lo, w_hi] rad/s) to the nearest fitted root of the same kind; +inf when one is unmatched.
double worst_root_error(const std::vector<Root>& truth, const std::vector<Root>& fit, double w_lo,
                        double w_hi);

/// Phase difference in degrees wrapped to (-180, 180].
double wrap_deg(double d);

/// The upper-triangular factor R (k x k, zeros below the diagonal) of a rows x k matrix with N(0,
/// 1) entries, column j scaled by 10^(-decades j / (k - 1)): R's condition is then that of a
/// weighted polynomial basis, as in an SK iteration (null_vector.h). With `dependent`, the last
/// column (before scaling) is a combination of the others plus `perturb` times N(0, 1) noise: a
/// null direction to s_min ~ perturb (noise-free SK data make such R at s_min ~ eps s_max).
Eigen::MatrixXd graded_triangular_factor(int rows, int k, unsigned seed, double decades,
                                         bool dependent = false, double perturb = 0);

/// Distance of a fitted root from the truth's relative to |truth| (the upper location of a pair);
/// infinite when one is real and the other a pair.
double root_error(const Root& fit, const Root& want);
/// The largest root_error over two lists in listing order (infinite when their sizes differ).
double worst_error(const std::vector<Root>& fit, const std::vector<Root>& want);

}  // namespace fralab::testing
