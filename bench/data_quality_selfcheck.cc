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
// Exit status 1 when named < --min-named or the clean cases' share without a flag <
// --min-clean. Deterministic in --seed.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "fralab/exchange/data_quality.h"
#include "fralab/exchange/tape_series.h"
#include "random_machine.h"
#include "test_util.h"

using namespace fralab;
using namespace fralab::testing;

namespace {

struct Injected {
  std::string channel;
  DataFaultKind kind;
  double size = 0;  // hum amplitude, drift rate, clock rate error (what `sized` compares); else 0
  std::string text;
};

AcquireOptions excitation() {
  AcquireOptions o = random_phase_multisine("0.05:20", 5, -1, 1);
  o.min_cycles = 3;
  return o;
}

TimeSeries measure(const Model& m, uint64_t seed) {
  const auto r = simulate_campaign(m, excitation(), true, seed);
  return blocks_to_series(r.blocks, m.name);
}

// Draws one fault on an output of `m` (sized from the clean recording `clean`), adds it to the
// model and returns what it is.
Injected draw_fault(Model& m, const TimeSeries& clean, std::mt19937_64& g) {
  std::uniform_int_distribution<size_t> pick_out(0, m.outputs.size() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ModelOutput& o = m.outputs[pick_out(g)];
  const int c = clean.channel_index(o.name);
  double lo = INFINITY, hi = -INFINITY, mean = 0, var = 0;
  for (int64_t k = 0; k < clean.n_samples; ++k) {
    const double v = clean.at(size_t(c), k);
    lo = std::min(lo, v), hi = std::max(hi, v);
    mean += v / double(clean.n_samples);
  }
  for (int64_t k = 0; k < clean.n_samples; ++k)
    var += std::pow(clean.at(size_t(c), k) - mean, 2) / double(clean.n_samples);
  const double sd = std::sqrt(var), T = double(clean.n_samples) / clean.sample_rate_hz;
  const double noise = std::max(o.noise_rms, 1e-3 * sd);
  Injected in;
  in.channel = o.name;
  ChannelFault f;
  switch (std::uniform_int_distribution<int>(0, 6)(g)) {
    case 0: {  // clipped at 60-90 % of the swing on one side or both
      f.kind = ChannelFaultKind::kClip;
      const double share = 0.6 + 0.3 * u(g);
      const int side = std::uniform_int_distribution<int>(0, 2)(g);
      if (side != 1) f.max = mean + share * (hi - mean);
      if (side != 0) f.min = mean - share * (mean - lo);
      in.kind = DataFaultKind::kClipping;
      in.text = "clip at " + significant(share * 100, 3) + " % of the swing";
      break;
    }
    case 1: {  // hum 0.5-5 noise rms at 50 or 60 Hz, with its 3rd harmonic half the time
      f.kind = ChannelFaultKind::kHum;
      f.frequency_hz = u(g) < 0.5 ? 50.0 : 60.0;
      f.amplitude = noise * (0.5 + 4.5 * u(g));
      if (u(g) < 0.5) f.harmonics = {1, 3};
      f.phase_deg = 360 * u(g);
      in.kind = DataFaultKind::kHum;
      in.size = f.amplitude;
      in.text = "hum " + significant(f.frequency_hz, 3) + " Hz x" +
                std::to_string(f.harmonics.size()) + ", " + significant(f.amplitude / noise, 3) +
                " noise rms";
      break;
    }
    case 2: {  // drift of 0.5-3 response sd over the run
      f.kind = ChannelFaultKind::kDrift;
      f.rate = (u(g) < 0.5 ? -1 : 1) * sd * (0.5 + 2.5 * u(g)) / T;
      in.kind = DataFaultKind::kDrift;
      in.size = f.rate;
      in.text = "drift " + significant(f.rate * T / sd, 3) + " sd over the run";
      break;
    }
    case 3:
    case 4: {  // dropouts, 0.2-3 a second, 1-20 samples, held or lost
      f.kind = ChannelFaultKind::kDropouts;
      f.rate_hz = 0.2 + 2.8 * u(g);
      f.length = 1 + int(20 * u(g));
      f.held = u(g) < 0.5;
      in.kind = f.held ? DataFaultKind::kHeld : DataFaultKind::kLost;
      in.text = std::string(f.held ? "held" : "lost") + " dropouts " + significant(f.rate_hz, 3) +
                "/s x " + std::to_string(f.length);
      break;
    }
    case 5: {  // dead from 30-80 % of the run
      f.kind = ChannelFaultKind::kDead;
      f.from_s = T * (0.3 + 0.5 * u(g));
      in.kind = DataFaultKind::kNoResponse;
      in.text = "dead from " + significant(f.from_s, 3) + " s";
      break;
    }
    default: {  // clock 1e-4 .. 1e-3 fast
      f.kind = ChannelFaultKind::kClock;
      f.rate_error = std::pow(10.0, -4 + u(g));
      in.kind = DataFaultKind::kClock;
      in.size = f.rate_error / (1 + f.rate_error);
      in.text = "clock " + significant(f.rate_error * 100, 3) + " % fast";
      break;
    }
  }
  for (const ChannelFault& x : o.faults)
    if (x.kind == f.kind) return draw_fault(m, clean, g);  // one of a kind per channel
  o.faults.push_back(f);
  return in;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-bench-dataquality: the data-quality checks' randomised self-check"};
  int cases = 60, clean_cases = 60;
  uint64_t seed = 1;
  double min_named = 0, min_clean = 0;
  app.add_option("--cases", cases, "cases with 1-2 recording faults")->capture_default_str();
  app.add_option("--clean", clean_cases, "cases without")->capture_default_str();
  app.add_option("--seed", seed, "the plants' and faults' seed")->capture_default_str();
  app.add_option("--min-named", min_named, "exit 1 below this share of faults named");
  app.add_option("--min-clean", min_clean, "exit 1 below this share of clean cases unflagged");
  CLI11_PARSE(app, argc, argv);
  int put = 0, named = 0, to_size = 0, sized = 0, false_named = 0, clean_flagged = 0;
  for (int i = 0; i < cases + clean_cases; ++i) {
    const bool faulty = i < cases;
    RandomCase rc = random_machine_case(seed, i, 0);
    Model engine = rc.engine;
    std::mt19937_64 g(seed * 7919 + uint64_t(i));
    std::vector<Injected> injected;
    if (faulty) {
      const TimeSeries clean = measure(engine, seed + uint64_t(i));
      const int n = std::uniform_int_distribution<int>(1, 2)(g);
      for (int k = 0; k < n; ++k) injected.push_back(draw_fault(engine, clean, g));
    }
    const auto r = simulate_campaign(engine, excitation(), true, seed + uint64_t(i));
    const TimeSeries s = blocks_to_series(r.blocks, rc.name);
    const DataQuality q = check_data_quality(s, Schedule{s.sample_rate_hz, rc.name, r.events});
    std::printf("%s%s:", faulty ? "fault " : "clean ", rc.name.c_str());
    for (const Injected& in : injected)
      std::printf(" [%s: %s]", in.channel.c_str(), in.text.c_str());
    std::printf("\n");
    std::vector<bool> matched(q.faults.size(), false);
    for (const Injected& in : injected) {
      ++put;
      const DataFault* hit = nullptr;
      for (size_t k = 0; k < q.faults.size(); ++k)
        if (q.faults[k].channel == in.channel && q.faults[k].kind == in.kind) {
          matched[k] = true;
          hit = hit ? hit : &q.faults[k];
        }
      named += hit != nullptr;
      if (hit && in.size != 0) {
        ++to_size;
        const bool ok = std::abs(hit->size - in.size) <= 0.1 * std::abs(in.size);
        sized += ok;
        if (!ok)
          std::printf("    sized %s %s: %g, put in %g\n", in.channel.c_str(), to_string(in.kind),
                      hit->size, in.size);
      }
      if (!hit) std::printf("    missed: %s %s\n", in.channel.c_str(), to_string(in.kind));
    }
    bool any = false;
    for (size_t k = 0; k < q.faults.size(); ++k) {
      if (matched[k]) continue;
      any = true;
      ++false_named;
      std::printf("    named, not put in: %s\n", q.faults[k].text.c_str());
    }
    if (!faulty) clean_flagged += any || !q.faults.empty();
    std::fflush(stdout);
  }
  const double named_share = put ? double(named) / put : 1.0;
  const double clean_share = clean_cases ? 1.0 - double(clean_flagged) / clean_cases : 1.0;
  std::printf(
      "\nnamed %d / %d (%.3f); sized within 10 %% %d / %d; named, not put in %d; clean cases "
      "flagged %d / %d (unflagged %.3f)\n",
      named, put, named_share, sized, to_size, false_named, clean_flagged, clean_cases,
      clean_share);
  return named_share < min_named || clean_share < min_clean ? 1 : 0;
}
