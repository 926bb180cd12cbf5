// The engine emulator's mathematics: a fralab-model/1 plant advanced sample by sample.
//
// Lockstep and sample-clocked: each call to step() consumes one command sample per input and
// produces exactly one sample of every channel; nothing depends on wall-clock time. Structure:
// each input's actuator tf (FohLti) feeds its nonlinearities, giving the actuator position; each
// path is simulated as one exact chain from the command (actuator * path * sensor, when the
// actuator is linear) or from the position samples (path * sensor, when it has nonlinearities), so
// every channel driven by one linear actuator shares the same hold factor and the ratio of any two
// of them is exact (see lti.h). Noise: white Gaussian, noise_rms per channel, from a seeded
// generator per channel: the same seed gives the same samples. Recording faults listed in the
// model (plant/faults.h) act on the channels after the noise; `stuck` on the actuator position.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "fralab/core/measurement_chain.h"
#include "fralab/plant/faults.h"
#include "fralab/plant/lti.h"
#include "fralab/plant/model.h"
#include "fralab/plant/nonlinearity.h"

namespace fralab {

struct SimulatorOptions {
  double sample_rate_hz = 1000.0;  // > 0
  uint64_t seed = 1;
  bool noise = true;  // false: every noise_rms treated as 0
  /// Throws InputError naming the bad option.
  void validate() const;
};

class Simulator {
 public:
  Simulator(const Model& model, const SimulatorOptions& options);

  /// Channel names in output order: positions (one per input, named as the input), then outputs.
  const std::vector<std::string>& channel_names() const { return names_; }
  size_t n_inputs() const { return inputs_.size(); }
  size_t n_channels() const { return names_.size(); }

  /// One sample. `commands` holds one absolute command per model input (model order);
  /// `channels` receives n_channels() absolute values. NaN or infinite commands throw InputError.
  void step(const double* commands, double* channels);
  int64_t samples_done() const { return k_; }
  void reset();

 private:
  struct InputChain {
    double dc = 0.0;
    std::unique_ptr<FohLti> actuator;  // null: identity
    std::vector<std::unique_ptr<Nonlinearity>> nl;
    double noise = 0.0;
    std::vector<std::pair<int, double>> coupling;    // (output index, gain)
    std::vector<std::pair<int64_t, int64_t>> stuck;  // [from, to) samples: the position held
    double held = 0.0;
  };
  struct PathChain {
    int input = 0;
    int output = 0;
    bool from_position = false;  // driven by the position (nonlinear actuator) or the command
    std::unique_ptr<FohLti> lti;
  };
  const Model model_;
  SimulatorOptions opt_;
  std::vector<std::string> names_;
  std::vector<InputChain> inputs_;
  std::vector<PathChain> paths_;
  std::vector<double> out_dc_, out_noise_;
  std::vector<std::mt19937_64> rng_;
  std::vector<double> du_, pos_, out_;
  std::vector<FaultyChannel> faulty_;       // per channel (empty when it has none)
  std::vector<std::pair<int, int>> swaps_;  // channel pairs exchanged after the faults
  int64_t k_ = 0;
};

/// The measurement chain of this emulator running model `m` at `sample_rate_hz`: first-order
/// hold, and the inputs whose actuator has a nonlinearity drive their paths from held position
/// samples. run.json records it as "measurement_chain"; fralab-acquire --emulator-chain puts it
/// on the tape.
MeasurementChain emulator_chain(const Model& m, double sample_rate_hz);

}  // namespace fralab
