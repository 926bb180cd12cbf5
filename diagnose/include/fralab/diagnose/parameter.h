// A finding's numeric parameters, typed: the keys of diagnosis.json's `parameters`
// (docs/formats.md §6 and §15) as an enum inside the diagnosis, their words only where JSON or a
// report is written or read (to_string / param_from_string).
#pragma once

#include <map>
#include <optional>
#include <string>

namespace fralab {

/// Declared in the alphabetical order of their words, so that a Parameters map lists them as
/// diagnosis.json's objects do (the order of every text the diagnosis writes).
enum class Param {
  kCol,                // col: a state model entry's column, 1-based
  kCornerRadS,         // corner_rad_s: a missing lag's or lead's corner, rad/s
  kDelayS,             // delay_s: a delay, s
  kFrom,               // from: a state model entry's simulated value
  kFromRadS,           // from_rad_s: a moved pole's simulated frequency (or real pole), rad/s
  kFromZeta,           // from_zeta: a moved pair's simulated damping
  kGain,               // gain: a missing path's or a measurement coupling's gain
  kGainDb,             // gain_db: measured over simulated, dB
  kNotch,              // notch: 1 when a missing resonance is a zero pair (a fit's, not reported)
  kPoles,              // poles: a missing path's pole count
  kRow,                // row: a state model entry's row, 1-based
  kSign,               // sign: a sign error's -1
  kTimeConstantFromS,  // time_constant_from_s: -1 / a diagonal entry of A, simulated, s
  kTimeConstantToS,    // time_constant_to_s: -1 / that entry as the data have it, s
  kTo,                 // to: a state model entry's value as the data have it
  kToRadS,             // to_rad_s: a moved pole's frequency as the data have it, rad/s
  kToZeta,             // to_zeta: a moved pair's damping as the data have it
  kWidth,              // width: a hysteresis' or a deadband's width, input units
  kWnRadS,             // wn_rad_s: a resonance's or a damping error's frequency, rad/s
  kZeros,              // zeros: a missing path's zero count
  kZeta,               // zeta: a resonance's or a moved pair's damping
};

/// A finding's (or a fitted cause's) parameters and their values.
using Parameters = std::map<Param, double>;

/// The word of diagnosis.json.
const char* to_string(Param p);
/// The parameter of a word; nullopt when it is none of docs/formats.md §6 and §15.
std::optional<Param> param_from_string(const std::string& word);

}  // namespace fralab
