// Plant speed: samples per second of the 95 % J85 (all four inputs excited, every channel), 1 kHz
// sample rate, one core. Counter "x_realtime" is simulated seconds per wall second.
#include <benchmark/benchmark.h>

#include <cmath>

#include "fralab/plant/simulator.h"

using namespace fralab;

static void BM_J85_95_Plant(benchmark::State& state) {
  Model m = load_model(std::string(FRALAB_SOURCE_DIR) + "/models/j85_95.json");
  SimulatorOptions opt;
  Simulator sim(m, opt);
  std::vector<double> u(4), y(sim.n_channels());
  int64_t k = 0;
  for (auto _ : state) {
    for (int i = 0; i < 4; ++i) {
      u[i] = m.dc(m.inputs[i].name) + 0.02 * m.inputs[i].full_scale * std::sin(0.01 * (i + 1) * k);
    }
    sim.step(u.data(), y.data());
    benchmark::DoNotOptimize(y.data());
    ++k;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["x_realtime"] = benchmark::Counter(double(state.iterations()) / opt.sample_rate_hz,
                                                    benchmark::Counter::kIsRate);
}
BENCHMARK(BM_J85_95_Plant);

BENCHMARK_MAIN();
