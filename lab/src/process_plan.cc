#include "fralab/lab/process_plan.h"

#include "fralab/acquire/acquire_flags.h"
#include "fralab/acquire/model_info.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/text.h"

namespace fralab {

namespace {

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}

// The deputy host that runs processes of `kind` ("" = this host).
std::string host_of(const MeasureOptions& o, const std::string& kind) {
  auto it = o.hosts.find(kind);
  return it == o.hosts.end() ? std::string() : it->second;
}

// The pair groups of input `x`, one analyser each: every position-relative pair (X:O and u_X:X)
// alone, and the command-relative pairs u_X:O together (they share the command as reference).
std::vector<std::vector<std::string>> analyser_groups(const std::string& x,
                                                      const std::vector<std::string>& outs) {
  const std::vector<std::string> pairs = pairs_for_input(x, outs);
  std::vector<std::vector<std::string>> groups;
  for (size_t k = 0; k <= outs.size(); ++k) groups.push_back({pairs[k]});
  groups.push_back(std::vector<std::string>(pairs.begin() + outs.size() + 1, pairs.end()));
  return groups;
}

}  // namespace

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
  const std::string tape = dir.tape(), engine_file = dir.engine();
  const std::vector<int> excite = select_inputs(model, o.acquire.inputs);
  std::vector<std::string> input_names, outs;
  for (int i : excite) input_names.push_back(model.inputs[i].name);
  for (const auto& out : model.outputs) outs.push_back(out.name);
  AcquireOptions ao = o.acquire;
  ao.inputs = join(input_names);
  auto start = [&](ProcessSpec spec) { plan.processes.push_back(std::move(spec)); };

  std::vector<std::string> rec = {
      program("fralab-record"), "--lcm-url", url, "--run-id", run_id, "--out", tape};
  if (o.resume)  // the tape is continued where it is whole
    rec.insert(rec.end(), {"--append", "--first-block", std::to_string(from.first_block),
                           "--first-status", std::to_string(from.first_status)});
  start({"recorder", rec, dir.log("recorder"), host_of(o, "recorder")});

  std::vector<std::string> plant = {program("fralab-plant"),
                                    "--model",
                                    engine_file,
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
                 {"--replay", tape, "--replay-blocks", std::to_string(from.first_block)});
  start({"plant", plant, dir.log("plant"), host_of(o, "plant")});

  plan.consumers = {"plant", "recorder"};
  plan.awaited = {"plant"};
  if (!o.resume) {
    for (const std::string& x : input_names) {
      for (const auto& g : analyser_groups(x, outs)) {
        const std::string name =
            "analyze-" + pair_file_stem(g.front()) + (g.size() > 1 ? "-cmd" : "");
        // At lower priority: they are flow-controlled like the plant and recorder.
        std::vector<std::string> args = {"nice",      "-n", "5",        program("fralab-analyze"),
                                         "--lcm-url", url,  "--run-id", run_id,
                                         "--name",    name, "--out",    o.out,
                                         "--linger",  "30"};
        for (const auto& p : g) args.insert(args.end(), {"--pair", p});
        start({name, args, dir.log(name), host_of(o, "analyze")});
        plan.consumers.push_back(name);
        plan.awaited.push_back(name);
      }
    }
    start({"identify",
           {program("fralab-identify"), "--lcm-url", url, "--run-id", run_id, "--expect",
            std::to_string(measured_pairs(model, excite).size()), "--out", o.out, "--delay",
            o.fit_delay, "--title", model.name + ": measured transfer matrix"},
           dir.log("identify"),
           host_of(o, "identify"),
           /*essential=*/false});
  }

  std::vector<std::string> acq = {program("fralab-acquire"),
                                  "--engine",
                                  engine_file,
                                  "--lcm-url",
                                  url,
                                  "--run-id",
                                  run_id,
                                  "--consumers",
                                  join(plan.consumers),
                                  "--stall-timeout",
                                  lossless(o.stall_timeout_s),
                                  "--first-block",
                                  std::to_string(from.first_block),
                                  "--first-status",
                                  std::to_string(from.first_status),
                                  "--summary",
                                  dir.acquire_summary(),
                                  "--chain",
                                  chain_to_json(emulator_chain(model, ao.sample_rate_hz)).dump()};
  for (const std::string& f : acquire_flags(ao)) acq.push_back(f);
  start({"acquire", acq, dir.log("acquire"), host_of(o, "acquire")});
  plan.awaited.push_back("acquire");
  return plan;
}

}  // namespace fralab
