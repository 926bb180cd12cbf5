// Writes the fuzz seed corpus (tests/fuzz/corpus/<reader>/seed*): small valid inputs made with
// the library code itself. Usage: fuzz_make_seeds DIR
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <numbers>

#include "fralab/core/frd.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/model.h"

using namespace fralab;

namespace {

// Writes LCM messages to a log file in order, as the recorder does.
struct TapeWriter {
  explicit TapeWriter(const std::string& path) : log(path, "w") {}
  template <class Msg>
  void operator()(const char* channel, const Msg& msg) {
    std::vector<uint8_t> buf(size_t(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, int(buf.size()));
    lcm::LogEvent ev{num++, 0, channel, int32_t(buf.size()), buf.data()};
    log.writeEvent(&ev);
  }
  lcm::LogFile log;
  int64_t num = 0;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const std::string d = argv[1];
  {  // A tape: start, integrate and done status, three tape blocks of 40 samples (a 25 Hz sine).
    TapeWriter put(d + "/tape/seed.tape");
    StatusEvent e;
    e.run_id = "seed";
    e.sample_rate_hz = 1000;
    e.inputs = {"Wf"};
    e.amplitudes = {1.0};
    e.frequency_hz = 25;
    e.state = RunState::kStart;
    e.seq = -1;
    put(kStatusChannel, to_status_msg(e));
    e.state = RunState::kIntegrate;
    e.seq = 0;
    e.sample = 0;
    e.n_samples = 120;
    e.n_cycles = 3;
    put(kStatusChannel, to_status_msg(e));
    for (int b = 0; b < 3; ++b) {
      Block blk;
      blk.run_id = "seed";
      blk.seq = b;
      blk.start_sample = 40 * b;
      blk.sample_rate_hz = 1000;
      blk.channels = {"u_Wf", "Wf", "P3"};
      blk.n_samples = 40;
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 40; ++k)
          blk.samples.push_back((c + 1) *
                                std::sin(2 * std::numbers::pi * 25 * (40 * b + k) / 1000));
      blk.final_block = b == 2;
      put(kTapeChannel, to_tape_msg(blk));
    }
    e.state = RunState::kDone;
    e.seq = 1;
    e.sample = 120;
    put(kStatusChannel, to_status_msg(e));
  }
  {  // An orthogonal multisine tape: inputs Wf and A8 on lines 1-3 of a 20-sample
     // period, two experiments (DFT phases 0 and pi for A8) of two periods, then done.
    TapeWriter put(d + "/tape/seed_orthogonal.tape");
    const int P = 20;
    StatusEvent e;
    e.run_id = "seed";
    e.sample_rate_hz = 1000;
    e.excitation = Excitation::kMultisine;
    e.inputs = {"Wf", "A8"};
    e.amplitudes = {1.0, 1.0};
    e.frequency_hz = 1000.0 / P;
    e.period_samples = P;
    e.lines = {1, 1, 2, 2, 3, 3};
    e.line_input = {0, 1, 0, 1, 0, 1};
    e.n_steps = 2;
    int64_t seq = 0;
    for (int x = 0; x < 2; ++x) {
      e.step = x;
      e.state = RunState::kIntegrate;
      e.seq = seq++;
      e.sample = 2 * P * x;
      e.n_samples = 2 * P;
      e.n_cycles = 2;
      put(kStatusChannel, to_status_msg(e));
    }
    for (int b = 0; b < 2; ++b) {
      Block blk;
      blk.run_id = "seed";
      blk.seq = b;
      blk.start_sample = 2 * P * b;
      blk.sample_rate_hz = 1000;
      blk.channels = {"u_Wf", "u_A8", "Wf", "A8", "P3"};
      blk.n_samples = 2 * P;
      std::vector<std::vector<double>> v(5, std::vector<double>(2 * P, 0.0));
      for (int n = 0; n < 2 * P; ++n)
        for (int k = 1; k <= 3; ++k) {
          const double ph = 2 * std::numbers::pi * k * n / P;
          v[0][n] += std::sin(ph + k);
          v[1][n] += std::sin(ph + k * k + std::numbers::pi * b);
        }
      for (int n = 0; n < 2 * P; ++n) {
        v[2][n] = 0.9 * v[0][n];
        v[3][n] = 0.8 * v[1][n];
        v[4][n] = 0.5 * v[2][n] - 0.25 * v[3][n];
      }
      for (const auto& c : v) blk.samples.insert(blk.samples.end(), c.begin(), c.end());
      blk.final_block = b == 1;
      put(kTapeChannel, to_tape_msg(blk));
    }
    e.state = RunState::kDone;
    e.seq = seq;
    e.sample = 4 * P;
    e.n_samples = 0;
    put(kStatusChannel, to_status_msg(e));
  }
  // A model: the smallest embedded-style plant, one input and one output.
  std::ofstream(d + "/model/seed.json") << R"({"format": "fralab-model/1", "name": "seed",
  "inputs": [{"name": "Wf", "units": "lb/hr", "full_scale": 3000,
    "actuator": {"tf": {"gain": 1, "poles": [{"wn": 134, "zeta": 0.172}]},
                 "nonlinearity": [{"type": "hysteresis", "width": 6}]}}],
  "outputs": [{"name": "P3", "units": "psi", "noise_rms": 0.01,
    "sensor": {"tf": {"gain": 1, "poles": [{"real": -50}]}}}],
  "paths": [{"output": "P3", "input": "Wf",
    "tf": {"gain": 0.03, "zeros": [{"real": 192}], "poles": [{"real": -2.8}], "delay_s": 0.011}}]}
)";
  // A model whose channels carry one recording fault of each kind (plant/faults.h).
  std::ofstream(d + "/model/seed_faults.json") << R"({"format": "fralab-model/1", "name": "faults",
  "operating_point": {"speed_pct": 95, "steady_state": {"P3": 70, "N": 15000}},
  "inputs": [{"name": "Wf", "units": "lb/hr", "full_scale": 3000,
    "faults": [{"kind": "stuck", "from_s": 0.5, "for_s": 0.3}, {"kind": "hum", "amplitude": 1}]}],
  "outputs": [{"name": "P3", "units": "psi", "noise_rms": 0.01,
    "faults": [{"kind": "clock", "rate_error": 0.001, "offset_s": 0.01},
               {"kind": "hum", "frequency_hz": 60, "amplitude": 0.1, "harmonics": [1, 3]},
               {"kind": "drift", "rate": 0.01, "from_s": 0.2}, {"kind": "clip", "max": 70.01},
               {"kind": "sign"}, {"kind": "scale", "factor": 6.894757},
               {"kind": "dropouts", "rate_hz": 20, "length": 3, "mode": "lost"},
               {"kind": "swap", "with": "N"}]},
              {"name": "N", "units": "rpm", "noise_rms": 1,
    "faults": [{"kind": "dead", "from_s": 1}, {"kind": "dropouts", "rate_hz": 5, "length": 2}]}],
  "paths": [{"output": "P3", "input": "Wf", "tf": {"gain": 0.03, "poles": [{"real": -2.8}]}},
            {"output": "N", "input": "Wf", "tf": {"gain": 2, "poles": [{"real": -1}]}}]}
)";
  // A state model (fralab-ss/1): two states, one input, two outputs, delays of each kind.
  std::ofstream(d + "/model/seed_ss.json") << R"({"format": "fralab-ss/1", "name": "seed",
 "states": [{"name": "N"}, {"name": "T4"}],
 "inputs": [{"name": "u", "units": "1", "full_scale": 1, "delay_s": 0.01}],
 "outputs": [{"name": "y", "units": "1"}, {"name": "z", "units": "1", "delay_s": 0.002}],
 "A": [[-3, 0.5], [0.2, -0.5]], "B": [[1], [0.5]], "C": [[1, 0], [0, 1]], "D": [[0], [0.01]],
 "delay_s": [[0], [0.001]]}
)";
  Frd f;
  f.pair = "Wf:P3";
  for (int i = 0; i < 4; ++i) {
    FrdPoint p;
    p.w = 0.5 * (i + 1);
    p.mag = 0.03 / (1 + i);
    p.phase_deg = -10.0 * i;
    p.sigma = 1e-4;
    p.coherence = 0.99;
    f.points.push_back(p);
  }
  save_frd(d + "/frd/seed.json", f);
  std::ofstream(d + "/csv/seed.csv")
      << "w,mag,phase_deg,sigma\n0.5,0.03,-1,0.001\n1,0.02,-5,0.001\n2,0.01,-20,0.001\n";
  // TFNS data cards: column 1 flag, 15-29 frequency, 30-44 and 45-59 the value's two parts.
  auto card = [](char flag, const std::string& f, const std::string& a, const std::string& b) {
    std::string l(60, ' ');
    l[0] = flag;
    l.replace(14, f.size(), f);
    l.replace(29, a.size(), a);
    l.replace(44, b.size(), b);
    return l + "\n";
  };
  std::ofstream(d + "/tfns/seed.deck")
      << "C        2         1     0.005      0.02       0.1      0.01\n*\n"
      << card(' ', "1.0", "20.0", "-45.0") << card(' ', "2.0", "16.0", "-60.0")
      << card('B', "H1.0", "M2.0", "R-1.2") << card('P', "R10.0", "1.0", "-1.5") << "*\n";
  return 0;
}
