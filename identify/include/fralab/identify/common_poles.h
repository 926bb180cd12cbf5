// Several measured curves fitted with one pole set (`fralab fit --frd A --frd B ...
// --common-poles`): the curves' grids checked to be one, their weights, the pole set
// (pole_set_fit.h), and the result per curve and together (docs/formats.md §25).
//
// Weights: a curve whose valid points all carry sigma is weighted 1 / sigma_i^2. Otherwise its
// noise is estimated as one absolute level from the data themselves: on a grid dense enough to
// resolve the response, the second difference g_{i+1} - 2 g_i + g_{i-1} is mostly noise, of
// variance 6 sigma^2 for white complex noise, and |.|^2 is then exponential, whose median is
// ln 2 times its mean: sigma^2 = median |second difference|^2 / (6 ln 2). The median keeps the
// few points where the response itself bends (a resonance's peak) from raising it. With a level
// estimated, "adequate" is judged against that level. Unweighted (scikit-rf's vector fitting):
// every point of every curve alike, sigma the rms of the curves' estimated levels.
//
// A relative floor (CommonPoleOptions::relative_floor): when the fit against sigma is not
// adequate, its misfit is the model's, not the noise's (a structure measured far better than any
// linear model of the allowed order fits it, its nonlinear distortion not in sigma). Weighted by
// 1 / sigma^2 such a fit spends its poles on the largest responses and misses the small ones (an
// antiresonance) by tens of percent. Each curve's relative floor rho_c is then taken from that
// fit, rho_c^2 = median over its points of max(0, |e|^2 - sigma^2) / |G|^2, and the pole set is
// fitted again on weights 1 / (sigma^2 + rho_c^2 |G|^2): every point counted by its relative error
// where the model dominates, by its noise where the noise does (docs/method/identifier.md §7b).
//
// The poles of the result are marked physical or not from a stabilisation diagram of the same
// weights (stabilisation.h).
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/json_util.h"
#include "fralab/identify/pole_set_fit.h"
#include "fralab/identify/stabilisation.h"

namespace fralab {

struct CommonPoleOptions {
  /// The pole set's loop; a structure's band can hold tens of modes, so up to 100 poles.
  PoleSetFitOptions fit{.max_poles = 100};
  /// Every point of every curve alike (scikit-rf's vector fitting): no sigma, no floor.
  bool unweighted = false;
  /// The relative floor above, when the fit against sigma is not adequate.
  bool relative_floor = true;
  /// The stabilisation diagram (rows up to the fit's order) and the poles marked physical.
  bool stabilisation = true;
  StabilisationOptions stability;
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct CommonPoleCurve {
  std::string source;  // file name, as given
  std::string pair;    // the curve's pair when its file names one
  bool sigma_given = false;
  double noise = -1;         // the estimated absolute noise level (sigma_given false)
  double rel_floor = 0;      // rho_c (0: none taken)
  double rms_error = 0;      // sqrt(mean |G_fit - G|^2) over its points
  double rms_value = 0;      // sqrt(mean |G|^2)
  double rms_log_error = 0;  // sqrt(mean |ln(G_fit / G)|^2) (the diagnosis' error metric)
};

struct CommonPoleResult {
  PoleSetFit fit;
  std::vector<CommonPoleCurve> curves;
  double rms_total = 0;      // sqrt(sum over curves of mean |G_fit - G|^2) (scikit-rf's figure)
  double rms_log_total = 0;  // sqrt(mean over every point of every curve of |ln(G_fit / G)|^2)
  bool floor_taken = false;  // the pole set was fitted again with the relative floor
  std::string fit_against_sigma;  // that first fit's message, when it was
  std::optional<StabilisationDiagram> diagram;
  std::vector<double> w;  // the grid fitted (the curves' valid points), rad/s
  std::vector<std::vector<std::complex<double>>> g;  // [curve][point] the values fitted
  std::vector<bool> physical;    // per pole of fit.poles (empty without a diagram)
  std::vector<int> stable_rows;  // per pole: the diagram's rows that hold it
};

/// The absolute noise level of a dense curve from its second differences (see above); -1 with
/// fewer than 3 points.
double second_difference_noise(const std::vector<std::complex<double>>& g);

/// Fits curves[c] (valid points only) with one pole set. Throws InputError naming the source when
/// a curve has fewer than 4 valid points or its valid frequencies differ from the first curve's
/// (relative 1e-9), naming the first point that differs.
CommonPoleResult fit_common_poles(const std::vector<Frd>& curves,
                                  const std::vector<std::string>& sources,
                                  const CommonPoleOptions& o = {});

/// docs/formats.md §25.
Json common_poles_to_json(const CommonPoleResult& r);

/// r's stabilisation diagram as a PNG (stabilisation.h's render_stabilisation_diagram: the
/// physical poles as lines, the curves fitted beneath). false without a diagram, or when gnuplot
/// is missing or fails.
bool render_common_poles_diagram(const CommonPoleResult& r, const std::string& png);

}  // namespace fralab
