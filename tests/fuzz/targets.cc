#include "targets.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "fralab/core/frd.h"
#include "fralab/exchange/schedule.h"
#include "fralab/exchange/time_series.h"
#include "fralab/identify/readers.h"
#include "fralab/identify/state_model.h"
#include "fralab/identify/transfer_matrix.h"
#include "fralab/plant/model.h"
#include "fralab/plant/simulator.h"
#include "random_shapes.h"
#include "tape_analysis.h"

namespace fralab::fuzz {

namespace {

std::string scratch(const std::string& reader) {
  static const std::string dir = [] {
    const auto d =
        std::filesystem::temp_directory_path() / ("fralab_fuzz_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d.string();
  }();
  return dir + "/input." + reader;
}

}  // namespace

int run(const std::string& reader, const uint8_t* data, size_t size) {
  const std::string path = scratch(reader);
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw std::runtime_error("cannot write " + path);
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  try {
    if (reader == "tape") {
      std::string warning;
      read_tape_file(
          path, [](const TapeEvent&) {}, &warning);
      AnalyzerOptions o;
      analyze_tape_file(path, {"u_Wf:Wf", "Wf:P3"}, o);
    } else if (reader == "model") {  // read, then run: its recording faults act at the clock
      const Model m = load_model(path);
      SimulatorOptions so;
      so.sample_rate_hz = 100;
      Simulator sim(m, so);
      std::vector<double> u(m.inputs.size()), y(sim.n_channels());
      for (size_t i = 0; i < u.size(); ++i) u[i] = m.dc(m.inputs[i].name);
      for (int k = 0; k < 200; ++k) {
        if (!u.empty()) u[0] += (k % 20 < 10 ? 1e-3 : -1e-3) * m.inputs[0].full_scale;
        sim.step(u.data(), y.data());
      }
    } else if (reader == "frd") {
      load_frd(path);
    } else if (reader == "csv") {
      read_frd_csv(path);
    } else if (reader == "tfns") {
      read_fit_input(path);
    } else if (reader == "series") {  // a recording to import, its clock and its reference
      const TimeSeries ts = to_time_series(read_csv_series(path, {}), 0);
      ReferenceScheduleOptions o;
      o.min_cycles = 1;
      o.min_integrate_s = 0;
      schedule_from_reference(ts, o);
    } else if (reader == "schedule") {
      load_schedule(path);
    } else if (reader == "shapes") {  // the bytes choose a set's shape: matrix and state model
      const auto set = testing::random_shape_set_from_bytes(data, size);
      const TransferMatrix m = build_transfer_matrix(set.entries);
      // Every code path of the state model with few sweeps: the default 500 take seconds per
      // draw under the sanitizers (identify_shapes_test runs the defaults, optimised).
      StateModelOptions so;
      so.max_sweeps = 12;
      so.rank_trial_sweeps = 4;
      const StateModel sm = build_state_model(m, set.data, so);
      state_model_json(sm);
      state_model_markdown(sm);
    } else {
      throw std::logic_error("no fuzz target " + reader);
    }
  } catch (const InputError&) {
    return 1;  // a clean refusal
  }
  return 0;
}

}  // namespace fralab::fuzz
