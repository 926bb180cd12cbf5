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
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/json_util.h"
#include "fralab/identify/pole_set_fit.h"

namespace fralab {

struct CommonPoleCurve {
  std::string source;  // file name, as given
  std::string pair;    // the curve's pair when its file names one
  bool sigma_given = false;
  double noise = -1;     // the estimated absolute noise level (sigma_given false)
  double rms_error = 0;  // sqrt(mean |G_fit - G|^2) over its points
  double rms_value = 0;  // sqrt(mean |G|^2)
};

struct CommonPoleResult {
  PoleSetFit fit;
  std::vector<CommonPoleCurve> curves;
  double rms_total = 0;  // sqrt(sum over curves of mean |G_fit - G|^2) (scikit-rf's figure)
};

/// The absolute noise level of a dense curve from its second differences (see above); -1 with
/// fewer than 3 points.
double second_difference_noise(const std::vector<std::complex<double>>& g);

/// Fits curves[c] (valid points only) with one pole set. Throws InputError naming the source when
/// a curve has fewer than 4 valid points or its valid frequencies differ from the first curve's
/// (relative 1e-9), naming the first point that differs.
CommonPoleResult fit_common_poles(const std::vector<Frd>& curves,
                                  const std::vector<std::string>& sources,
                                  const PoleSetFitOptions& o = {}, bool unweighted = false);

/// docs/formats.md §25.
Json common_poles_to_json(const CommonPoleResult& r);

}  // namespace fralab
