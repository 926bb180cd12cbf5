#include "fralab/lab/process_plan.h"

#include <algorithm>
#include <cstdlib>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/acquire/model_info.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/text.h"

namespace fralab {

namespace {

// The deputy host that runs processes of `kind` ("" = this host).
std::string host_of(const MeasureOptions& o, const std::string& kind) {
  auto it = o.hosts.find(kind);
  return it == o.hosts.end() ? std::string() : it->second;
}

// fralab-plant's command line: the engine, the seed and sample rate, free running on its own
// clock or stepped by the acquisition, and on a resumed run the tape's blocks replayed.
std::vector<std::string> plant_args(const MeasureOptions& o, const AcquireOptions& ao,
                                    const std::string& run_id, const std::string& url,
                                    const ResumePoint& from, const ModuleResolver& program) {
  const MeasureDir dir(o.out);
  std::vector<std::string> plant = {program("fralab-plant"),
                                    "--model",
                                    dir.engine(),
                                    "--lcm-url",
                                    url,
                                    "--seed",
                                    std::to_string(o.seed),
                                    "--run-id",
                                    run_id,
                                    "--sample-rate",
                                    lossless(ao.sample_rate_hz)};
  if (o.no_noise) plant.push_back("--no-noise");
  if (ao.free_running)  // on its own clock, a tape block per command block's length
    plant.insert(plant.end(),
                 {"--free-running", "--speed", lossless(ao.speed), "--tick",
                  std::to_string(ao.block), "--jitter-ms", lossless(o.plant_jitter_ms)});
  if (o.resume)  // the blocks on the tape replayed, to stand where the run stood
    plant.insert(plant.end(),
                 {"--replay", dir.tape(), "--replay-blocks", std::to_string(from.first_block)});
  return plant;
}

// fralab-acquire's command line: the engine, the consumers it waits for, where a resumed run
// starts, its summary file, and the campaign's flags (acquire_flags).
std::vector<std::string> acquire_args(const MeasureOptions& o, const AcquireOptions& ao,
                                      const std::string& run_id, const std::string& url,
                                      const ResumePoint& from,
                                      const std::vector<std::string>& consumers,
                                      const ModuleResolver& program) {
  const MeasureDir dir(o.out);
  std::vector<std::string> acq = {program("fralab-acquire"),
                                  "--engine",
                                  dir.engine(),
                                  "--lcm-url",
                                  url,
                                  "--run-id",
                                  run_id,
                                  "--consumers",
                                  join_list(consumers, ","),
                                  "--stall-timeout",
                                  lossless(o.stall_timeout_s),
                                  "--first-block",
                                  std::to_string(from.first_block),
                                  "--first-status",
                                  std::to_string(from.first_status),
                                  "--summary",
                                  dir.acquire_summary(),
                                  "--emulator-chain"};
  for (const std::string& f : acquire_flags(ao)) acq.push_back(f);
  return acq;
}

}  // namespace

AnalyserGrouping AnalyserGrouping::parse(const std::string& word) {
  AnalyserGrouping g;
  if (word == "pair") {
    g.by = By::kPair;
    return g;
  }
  if (word == "input") {
    g.by = By::kInput;
    return g;
  }
  char* end = nullptr;
  const long n = std::strtol(word.c_str(), &end, 10);
  if (word.empty() || *end != '\0' || n < 1 || n > 100000)
    throw InputError("--analysers \"" + word + "\": pair, input or a number of pairs >= 1");
  g.by = By::kCount;
  g.pairs = int(n);
  return g;
}

std::string AnalyserGrouping::str() const {
  return by == By::kPair ? "pair" : by == By::kInput ? "input" : std::to_string(pairs);
}

std::vector<AnalyserGroup> analyser_groups(const std::vector<std::string>& inputs,
                                           const std::vector<std::string>& outs,
                                           const AnalyserGrouping& g) {
  std::vector<AnalyserGroup> groups;
  std::vector<std::string> all;
  for (const std::string& x : inputs) {
    const std::vector<std::string> pairs = pairs_for_input(x, outs);
    all.insert(all.end(), pairs.begin(), pairs.end());
    if (g.by == AnalyserGrouping::By::kInput) {
      groups.push_back({"analyze-" + x, pairs});
    } else if (g.by == AnalyserGrouping::By::kPair) {
      // Per pairs_for_input: X:O for every output and u_X:X first, then the u_X:O.
      for (size_t k = 0; k <= outs.size(); ++k)
        groups.push_back({"analyze-" + pair_file_stem(pairs[k]), {pairs[k]}});
      const std::vector<std::string> cmd(pairs.begin() + outs.size() + 1, pairs.end());
      if (!cmd.empty())
        groups.push_back(
            {"analyze-" + pair_file_stem(cmd.front()) + (cmd.size() > 1 ? "-cmd" : ""), cmd});
    }
  }
  if (g.by == AnalyserGrouping::By::kCount)
    for (size_t k = 0; k < all.size(); k += size_t(g.pairs))
      groups.push_back(
          {"analyze-" + std::to_string(k / size_t(g.pairs) + 1),
           std::vector<std::string>(all.begin() + k,
                                    all.begin() + std::min(all.size(), k + size_t(g.pairs)))});
  return groups;
}

std::vector<std::string> measured_pairs(const Model& m, const std::vector<int>& inputs) {
  std::vector<std::string> outs, all;
  for (const auto& out : m.outputs) outs.push_back(out.name);
  for (int i : inputs) {
    const auto pairs = pairs_for_input(m.inputs[i].name, outs);
    all.insert(all.end(), pairs.begin(), pairs.end());
  }
  return all;
}

ProcessPlan plan_processes(const Model& model, const MeasureOptions& o, const std::string& run_id,
                           const std::string& url, const ResumePoint& from,
                           const ModuleResolver& program) {
  ProcessPlan plan;
  if (from.complete) return plan;  // the tape holds everything: nothing to start
  const MeasureDir dir(o.out);
  const std::vector<int> excite = select_inputs(model, o.acquire.inputs);
  std::vector<std::string> input_names, outs;
  for (int i : excite) input_names.push_back(model.inputs[i].name);
  for (const auto& out : model.outputs) outs.push_back(out.name);
  AcquireOptions ao = o.acquire;
  ao.inputs = join_list(input_names, ",");
  ao.block = block_samples(model, ao);  // the number every process is given
  auto start = [&](ProcessSpec spec) { plan.processes.push_back(std::move(spec)); };

  std::vector<std::string> rec = {
      program("fralab-record"), "--lcm-url", url, "--run-id", run_id, "--out", dir.tape()};
  if (o.resume)  // the tape is continued where it is whole
    rec.insert(rec.end(), {"--append", "--first-block", std::to_string(from.first_block),
                           "--first-status", std::to_string(from.first_status)});
  start({"recorder", rec, dir.log("recorder"), host_of(o, "recorder")});

  start({"plant", plant_args(o, ao, run_id, url, from, program), dir.log("plant"),
         host_of(o, "plant")});

  plan.consumers = {"plant", "recorder"};
  plan.awaited = {"plant"};
  if (!o.resume) {
    for (const AnalyserGroup& g : analyser_groups(input_names, outs, o.analysers)) {
      // At lower priority: they are flow-controlled like the plant and recorder.
      std::vector<std::string> args = {"nice",      "-n",   "5",        program("fralab-analyze"),
                                       "--lcm-url", url,    "--run-id", run_id,
                                       "--name",    g.name, "--out",    o.out,
                                       "--linger",  "30"};
      for (const auto& p : g.pairs) args.insert(args.end(), {"--pair", p});
      start({g.name, args, dir.log(g.name), host_of(o, "analyze")});
      plan.consumers.push_back(g.name);
      plan.awaited.push_back(g.name);
    }
    if (o.fit)
      start({"identify",
             {program("fralab-identify"), "--lcm-url", url, "--run-id", run_id, "--expect",
              std::to_string(measured_pairs(model, excite).size()), "--out", o.out, "--delay",
              o.fit_delay, "--title", model.name + ": measured transfer matrix"},
             dir.log("identify"),
             host_of(o, "identify"),
             /*essential=*/false});
  }

  start({"acquire", acquire_args(o, ao, run_id, url, from, plan.consumers, program),
         dir.log("acquire"), host_of(o, "acquire")});
  plan.awaited.push_back("acquire");
  return plan;
}

}  // namespace fralab
