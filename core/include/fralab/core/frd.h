// Frequency-response data, `fralab-frd/1` (docs/formats.md §4): the pair "E1:E2" (response E2/E1)
// and its points. w in rad/s, mag the amplitude ratio |E2/E1| (not dB), phase_deg the phase of E2
// relative to E1 in degrees, sigma the standard deviation of the complex ratio, coherence
// in [0, 1]. fralab adds f_hz, h2_rel/h3_rel (harmonic distortion of E2), n_cycles, step, input,
// valid and note; readers ignore what they do not know.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"

namespace fralab {

inline constexpr const char* kFrdFormat = "fralab-frd/1";

struct FrdPoint {
  double w = 0.0;
  double mag = 0.0;
  double phase_deg = 0.0;
  double sigma = -1.0;      // < 0: unknown
  double coherence = -1.0;  // < 0: unknown
  double h2_rel = 0.0;
  double h3_rel = 0.0;
  double nl_rel = -1.0;  // multisine: level on non-excited lines relative to the line (< 0: n/a)
  // A best linear approximation over random-phase realisations (analyze/bla.h): sigma is then the
  // total standard deviation of the mean, sigma^2 = sigma_noise^2 + sigma_nl^2, split into its
  // measurement-noise and stochastic-nonlinear parts (< 0: not separated, one realisation);
  // realisations: how many were averaged (0: a single measurement).
  double sigma_noise = -1.0;
  double sigma_nl = -1.0;
  int realisations = 0;
  // A multisine's point: the excited input's command amplitude on this line (peak, input units;
  // 0: not a multisine or unknown). What a nonlinearity's best linear approximation depends on.
  double line_amplitude = 0.0;
  int n_cycles = 0;
  int step = -1;
  std::string input;       // the excited input
  double amplitude = 0.0;  // excitation amplitude of that input (peak, input units)
  bool valid = true;
  std::string note;

  std::complex<double> value() const;  // mag * e^{j phase}
};

struct Frd {
  std::string pair;  // "E1:E2"
  std::vector<FrdPoint> points;
  std::string source;
};

/// Largest |E2/E1| a point may claim: beyond it a magnitude is nonsense (a corrupt file), refused.
inline constexpr double kMaxFrdMagnitude = 1e12;

/// What is numerically wrong with a point, "" when nothing: w not finite or <= 0; mag not finite,
/// < 0 or > kMaxFrdMagnitude; phase not finite; a sigma given (>= 0) that is not finite or is 0;
/// a coherence given (>= 0) that is not finite or exceeds 1 (+1e-9 for rounding); a sigma_noise
/// or sigma_nl given (>= 0) that is not finite; realisations < 0; a line_amplitude < 0 or not
/// finite.
std::string frd_point_problem(const FrdPoint& p);

/// Splits "E1:E2"; InputError naming the text otherwise.
std::pair<std::string, std::string> split_pair(const std::string& pair);
/// "E1_E2", the file stem of a pair.
std::string pair_file_stem(const std::string& pair);

Json frd_to_json(const Frd& frd);
/// Reads fralab-frd/1; errors name the file and JSON path. Invalid points are kept (valid=false).
Frd frd_from_json(const Json& j, const std::string& source);
Frd load_frd(const std::string& file);
void save_frd(const std::string& file, const Frd& frd);

}  // namespace fralab
