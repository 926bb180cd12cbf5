// What the acquisition needs to know of the engine model: which inputs to excite, at what
// amplitude, and how slow the plant is (for settle times). Pure functions, no I/O.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "fralab/acquire/campaign.h"
#include "fralab/plant/model.h"

namespace fralab {

/// "LO:HI" in Hz -> (LO, HI); InputError naming the text otherwise.
std::pair<double, double> parse_band(const std::string& band);

/// Largest time constant of a tf's poles, seconds: 1/|r| for a real pole r, 1/(zeta wn) for a
/// pair (its envelope); 0 without poles.
double slowest_time_constant_s(const Tf& tf);

/// The same over every tf in the model (actuators, sensors, paths).
double slowest_time_constant_s(const Model& m);

/// Damping ratio below which a pole pair is a light mode the multisine zooms on.
inline constexpr double kLightZeta = 0.1;

/// The model's light modes (pole pairs of zeta < max_zeta in its actuators, sensors and paths)
/// whose frequency wn / 2 pi lies in [f_lo_hz, f_hi_hz], sorted by wn; pairs within 1 % of each
/// other in wn are one mode, of the lightest damping among them (a mode every path carries, or
/// fitted path by path to slightly different values).
std::vector<ZoomMode> light_modes(const Model& m, double f_lo_hz, double f_hi_hz,
                                  double max_zeta = kLightZeta);

/// Indices of the inputs named in a comma-separated list ("" = every input, in model order).
/// InputError naming an unknown input and listing the known ones.
std::vector<int> select_inputs(const Model& m, const std::string& csv);

/// Every input with its DC and test amplitude: amplitude_pct of full scale when >= 0, else the
/// input's test_amplitude_pct, else 2 %; times `scale` (a second-amplitude measurement).
std::vector<CampaignInput> campaign_inputs(const Model& m, double amplitude_pct,
                                           double scale = 1.0);

}  // namespace fralab
