// fralab-bench-dataquality: the data-quality checks' randomised self-check. Plants shaped like
// machines (tests/util/random_machine.h, nothing hidden in the model) are measured in-process by
// an orthogonal multisine (the same library code as fralab-acquire and fralab-plant:
// tests/util/test_util.h simulate_campaign); --cases of them with 1-2 recording faults drawn at
// random (plant/faults.h: clip, hum, drift, held or lost samples, a dead channel, a clock error;
// channel, time and size at random, each large enough to matter to the curves), --clean of them
// without. Prints per case what was put in and what the checks named, then:
//   named: faults named on their channel with their kind / faults put in;
//   sized: hum amplitude, drift rate, clock rate error within 10 % / those named;
//   false: faults named that were not put in (a fault case's other channels and kinds);
//   clean flagged: clean cases with anything named / clean cases.
// Exit status 1 when named < --min-named, false > --max-false or the clean cases' share without
// a flag < --min-clean. Deterministic in --seed.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "fralab/exchange/data_quality.h"
#include "fralab/exchange/tape_series.h"
#include "random_faults.h"
#include "random_machine.h"
#include "test_util.h"

using namespace fralab;
using namespace fralab::testing;

namespace {

AcquireOptions excitation() {
  AcquireOptions o = random_phase_multisine("0.05:20", 5, -1, 1);
  o.min_cycles = 3;
  return o;
}

TimeSeries measure(const Model& m, uint64_t seed) {
  const auto r = simulate_campaign(m, excitation(), true, seed);
  return blocks_to_series(r.blocks, m.name);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-bench-dataquality: the data-quality checks' randomised self-check"};
  int cases = 60, clean_cases = 60;
  uint64_t seed = 1;
  double min_named = 0, min_clean = 0;
  int max_false = -1;
  app.add_option("--cases", cases, "cases with 1-2 recording faults")->capture_default_str();
  app.add_option("--clean", clean_cases, "cases without")->capture_default_str();
  app.add_option("--seed", seed, "the plants' and faults' seed")->capture_default_str();
  app.add_option("--min-named", min_named, "exit 1 below this share of faults named");
  app.add_option("--min-clean", min_clean, "exit 1 below this share of clean cases unflagged");
  app.add_option("--max-false", max_false,
                 "exit 1 when more faults than this are named that were not put in (-1: any)");
  CLI11_PARSE(app, argc, argv);
  FaultScore total;
  int clean_flagged = 0;
  for (int i = 0; i < cases + clean_cases; ++i) {
    const bool faulty = i < cases;
    RandomCase rc = random_machine_case(seed, i, 0);
    Model engine = rc.engine;
    std::mt19937_64 g(seed * 7919 + uint64_t(i));
    std::vector<InjectedFault> injected;
    if (faulty) {
      const TimeSeries clean = measure(engine, seed + uint64_t(i));
      const int n = std::uniform_int_distribution<int>(1, 2)(g);
      for (int k = 0; k < n; ++k) injected.push_back(add_random_fault(engine, clean, g));
    }
    const auto r = simulate_campaign(engine, excitation(), true, seed + uint64_t(i));
    const TimeSeries s = blocks_to_series(r.blocks, rc.name);
    const DataQuality q = check_data_quality(s, Schedule{s.sample_rate_hz, rc.name, r.events});
    std::printf("%s%s:", faulty ? "fault " : "clean ", rc.name.c_str());
    for (const InjectedFault& in : injected)
      std::printf(" [%s: %s]", in.channel.c_str(), in.text.c_str());
    std::printf("\n");
    const FaultScore fs = score_faults(injected, q.faults);
    total.add(fs);
    for (const std::string& l : fs.lines) std::printf("    %s\n", l.c_str());
    if (!faulty) clean_flagged += !q.faults.empty();
    std::fflush(stdout);
  }
  const double named_share = total.put ? double(total.named) / total.put : 1.0;
  const double clean_share = clean_cases ? 1.0 - double(clean_flagged) / clean_cases : 1.0;
  std::printf(
      "\nnamed %d / %d (%.3f); sized within 10 %% %d / %d; named, not put in %d; clean cases "
      "flagged %d / %d (unflagged %.3f)\n",
      total.named, total.put, named_share, total.sized, total.to_size, total.false_named,
      clean_flagged, clean_cases, clean_share);
  const bool too_many_false = max_false >= 0 && total.false_named > max_false;
  return named_share < min_named || clean_share < min_clean || too_many_false ? 1 : 0;
}
