// A generator of random plants for the diagnosis's self-check: sizes 1-3 inputs x 2-4
// outputs, random names, dynamics, actuators with and without position noise, sensors, noise
// levels; each case hides 0-2 effects drawn from the catalogue into the engine and says what the
// diagnosis must find (cause, place, parameter, tolerance). Deterministic in the seed.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fralab/diagnose/diagnose.h"
#include "fralab/plant/model.h"

namespace fralab::testing {

/// One hidden effect: the finding that names it (cause, scope, input/output as in docs/formats.md
/// §6) and its parameter `param` with value and tolerance (absolute `tol_abs` or relative
/// `tol_rel`).
struct HiddenEffect {
  CauseKind cause;
  Scope scope;
  std::string input, output;
  std::optional<Param> param;  // nullopt: a cause without one (a sign error, a whole path)
  double value = 0;
  double tol_abs = 0, tol_rel = 0;
  /// Text parameters the finding must carry with these values (a state model's entry: its
  /// `matrix` and `state`), and parameters it must carry exactly (the entry's `row` and `col`).
  std::map<std::string, std::string> text;
  std::map<Param, double> exact;
  /// Parameters that say which of the simulation's roots the effect moves (a pole_shift's
  /// from_rad_s, a damping_error's wn_rad_s), matched within 0.1 %.
  std::map<Param, double> at;
  std::string describe() const;
  /// Whether a finding names this effect at its place within tolerance.
  bool matches(const Finding& f) const;
};

struct RandomCase {
  std::string name;
  Model simulation, engine;
  std::vector<HiddenEffect> hidden;
};

/// Case `index` of the sequence drawn from `seed`; n_hidden < 0: 0-2 at random.
RandomCase random_case(uint64_t seed, int index, int n_hidden = -1);

/// Sets a hidden effect's parameter in `engine` (as random_case made it, e.value the value it
/// holds) to `value`: the same element moved (a delay, a corner, a gain in dB, a moved pole, a
/// backlash width, a resonance's wn, a damping). false for an effect without such a parameter
/// (sign_error, missing_path) or when the element is not found.
bool set_hidden_parameter(Model& engine, const HiddenEffect& e, double value);

/// Precision and recall of a diagnosis against a case's hidden effects.
struct Score {
  int findings = 0, true_findings = 0, hidden = 0, found = 0;
  /// Hidden effects found with a two-sided interval on their parameter, and those whose true
  /// value lies inside the 2-sigma interval, taken from the reported 1-sigma one as
  /// [v - 2 (v - lo), v + 2 (hi - v)] around the finding's value v.
  int with_interval = 0, in_two_sigma = 0;
  std::vector<std::string> false_findings, missed, outside_two_sigma;
};
Score score(const RandomCase& c, const std::vector<Finding>& findings);
/// f's 2-sigma interval on `param`, from its reported 1-sigma one [lo, hi] around its value v:
/// [v - 2 (v - lo), v + 2 (hi - v)]; nullopt when f has no value or no two-sided interval there.
std::optional<std::array<double, 2>> two_sigma_interval(const Finding& f,
                                                        std::optional<Param> param);

}  // namespace fralab::testing
