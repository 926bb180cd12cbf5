// Analyser speed: the Fourier-filter kernel (samples per second per channel: two multiply-adds per
// sample against the precomputed reference) and the offline analysis of a 14-channel tape file in
// multiples of real time.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "fralab/analyze/fourier_filter.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/tape_file.h"
#include "tape_analysis.h"

using namespace fralab;

static void BM_FourierKernel(benchmark::State& state) {
  const size_t n = 1 << 16;
  Reference ref = make_reference(n, 0.1, 2 * std::numbers::pi * 37 / n);
  std::vector<double> x(n);
  for (size_t k = 0; k < n; ++k) x[k] = std::sin(0.01 * k) + 1e-3 * k;
  double c, s;
  for (auto _ : state) {
    fourier_sums(x.data(), ref.c.data(), ref.s.data(), n, &c, &s);
    benchmark::DoNotOptimize(c);
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * n);  // samples per second, one channel
}
BENCHMARK(BM_FourierKernel);

static void BM_ReferenceRecurrence(benchmark::State& state) {
  const size_t n = 1 << 16;
  for (auto _ : state) {
    Reference r = make_reference(n, 0.1, 0.0123);
    benchmark::DoNotOptimize(r.c.data());
  }
  state.SetItemsProcessed(int64_t(state.iterations()) * n);
}
BENCHMARK(BM_ReferenceRecurrence);

// Offline tape analysis: FRALAB_BENCH_TAPE names a tape (bench/run_benchmarks.sh records one with
// `fralab measure`); every position-relative pair of Wf is analysed. Counter x_realtime = engine
// seconds on the tape per wall second.
static void BM_OfflineTape(benchmark::State& state) {
  const char* tape = std::getenv("FRALAB_BENCH_TAPE");
  if (!tape || !std::filesystem::exists(tape)) {
    state.SkipWithError("set FRALAB_BENCH_TAPE to a tape recorded by fralab measure");
    return;
  }
  std::vector<std::string> pairs = {"Wf:N", "Wf:P3", "Wf:DPP3", "Wf:P5", "Wf:T5", "u_Wf:Wf"};
  double engine_s = 0;
  for (auto _ : state) {
    auto frds = analyze_tape_file(tape, pairs, AnalyzerOptions{});
    benchmark::DoNotOptimize(frds.data());
  }
  // Engine time on the tape from its summary (samples / rate), computed once.
  int64_t samples = 0;
  double fs = 1000;
  read_tape_file(tape, [&](const TapeEvent& ev) {
    if (ev.channel != kTapeChannel) return;
    lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
    Block b = decode_tape_block(&rb, ev.channel);
    samples += b.n_samples;
    fs = b.sample_rate_hz;
  });
  engine_s = samples / fs;
  state.counters["x_realtime"] =
      benchmark::Counter(engine_s * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["channels"] = 15;
}
BENCHMARK(BM_OfflineTape)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
