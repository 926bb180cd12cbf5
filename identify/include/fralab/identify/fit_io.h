// Fitting a set of curves and writing the results the way `fralab measure` and `fralab fit` lay
// them out: DIR/tf/<E1>_<E2>.json per pair and DIR/transfer_matrix.{json,md}.
#pragma once

#include <string>
#include <vector>

#include "fralab/analyze/bode_plot.h"
#include "fralab/identify/transfer_matrix.h"

namespace fralab {

/// "auto", "none" or a number of seconds -> options; InputError naming the text otherwise.
void parse_delay_option(const std::string& text, FitOptions* o);

/// Fits every curve, writes DIR/tf/<stem>.json for each and the transfer matrix of the pairs whose
/// E1 is an input position and E2 an output (u_X:X actuator fits are listed beside it). Returns the
/// fits in the order of `curves`.
std::vector<FitResult> fit_and_write(const std::vector<Frd>& curves, const FitOptions& o,
                                     const std::string& dir, const std::string& title);

/// The `fralab fit` output file: fit_to_json, and when roots are deleted (TFNS P/Z cards, e.g.
/// "P03"), "deleted" with the kept zeros and poles. *kept receives the tf after deletion.
Json fit_output_json(const FitResult& r, const std::string& pair,
                     const std::vector<std::string>& deletions, Tf* kept);

/// TFNS's cross-plot of `data` against `fit` (and against `after_deletion` when given): the valid
/// points sorted by frequency, sigma bars when every valid point carries sigma > 0. Titled
/// "<pair or source>: data and fit"; `stem` names its files.
BodePlot fit_cross_plot(const Frd& data, const std::string& source, const Tf& fit,
                        const Tf* after_deletion, const std::string& stem);

}  // namespace fralab
