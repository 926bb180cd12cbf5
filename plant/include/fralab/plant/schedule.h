// A plant across its operating points: a model set (one fralab-model/1 per point, each with its
// operating point) and the model between two of its points, so that the emulator can run an engine
// where nobody measured it (`--engine j85@90`, or `--engine j85 --operating-point 90`).
//
// Spec form, accepted wherever a model is read (load_model_or_embedded): `SET@X` or
// `SET@KEY=X`, SET as in load_model_set, X the scheduling variable's value (KEY, default
// speed_pct, a number of the models' operating_point).
//
// Interpolation between the neighbours lo (x_lo) and hi (x_hi) of x, t = (x - x_lo) / (x_hi -
// x_lo) in (0, 1); at a member's own x the member itself, unchanged:
// - The channels must match: the same inputs and outputs with the same units, an input's
//   nonlinearities of the same types in the same order; anything else is refused naming the
//   channel and both models (or, with `common_channels_only`, left out and said in warnings).
// - Each tf (path, actuator, sensor; an absent actuator or sensor is the identity) root by root
//   along its track: the zeros of lo with those of hi, the poles likewise, real with real and pair
//   with pair, nearest first on a log scale of |root| (wn for a pair). A matched real root moves
//   by its time constant tau = -1/r, geometrically (log tau linear in t) when both have one sign,
//   linearly otherwise (a zero crossing the right half plane passes through infinity, where its
//   factor is 1); a pair by wn geometrically and zeta linearly. A pair left at one point and the
//   one or two real roots left nearest it at the other are one quadratic factor a2 s^2 + a1 s + 1
//   (one real root: a2 = 0), its coefficients linear in t (a pair that splits into two real
//   roots; the interpolated tf is then proper when both are). A root with no partner fades:
//   r/(1-t) (a root of lo) or r/t (of hi), its factor 1 - s/r tending to 1 where the other model
//   lacks it: the response is continuous in t and equals each member's at its point. Gains
//   geometrically when of one sign, linearly otherwise; delays linearly. A path present at one
//   point only is that path with its gain scaled to 0 at the other.
// - Everything else that is a number (steady state, full scales, noise, nonlinearity widths and
//   rates, measurement couplings, the operating point's own numbers) linearly.
// Stable poles stay stable (tau > 0 and zeta > 0 are kept by both rules). The result is checked
// as a model file is (parse_model).
//
// Units: x in the operating point's units (speed_pct: % N/Nmax); roots rad/s, delays s.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "fralab/plant/model.h"

namespace fralab {

struct SetModel {
  std::string spec;  // file path or embedded name
  double x = 0;      // the scheduling variable at this point
  Model model;
};

/// The scheduling variable of a model: speed_pct (Model::speed_pct, > 0) or a number of its
/// operating_point. InputError naming the model when it has none.
double operating_point_of(const Model& m, const std::string& schedule_by = "speed_pct");

/// The models a SET names, sorted by their scheduling variable: an embedded family ("j85":
/// j85_70, j85_85, j85_95; "j85_sim": the _sim models), a comma-separated list of files or
/// embedded names, a folder of model files (*.json), or one model. InputError naming the model
/// without the operating-point key, two models at one x, or a SET that names nothing.
std::vector<SetModel> load_model_set(const std::string& set,
                                     const std::string& schedule_by = "speed_pct");

struct ModelAt {
  std::string set;
  std::string schedule_by = "speed_pct";
  double x = 0;
};
/// "SET@X" / "SET@KEY=X" (the last '@'); nullopt when `spec` has no '@'. InputError for an
/// '@' followed by no finite number.
std::optional<ModelAt> parse_model_at(const std::string& spec);

struct InterpolationOptions {
  std::string schedule_by = "speed_pct";
  /// Channels present at one point only are left out (said in Model::warnings) instead of
  /// refused: the leave-one-out comparison, which measures the rest.
  bool common_channels_only = false;
};

/// The model at x between lo and hi (lo.x < x < hi.x), as the file comment says.
Model interpolate_models(const SetModel& lo, const SetModel& hi, double x,
                         const InterpolationOptions& o = {});

/// The model at x: the member at x itself, else interpolated between its neighbours. InputError
/// for x outside the set's range (no extrapolation), naming the range.
Model model_at(const std::vector<SetModel>& set, double x, const InterpolationOptions& o = {});

}  // namespace fralab
