// `fralab measure`: plant, acquisition, analysers and identifier on one engine; tape and frd files.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "commands.h"

namespace fralab {

void add_measure_flags(CLI::App* c, MeasureOptions& m) {
  add_acquire_flags(c, m.acquire, &m.auto_campaign);
  c->add_option("--seed", m.seed, "plant noise seed")->capture_default_str();
  c->add_option("--lcm-url", m.lcm_url, "LCM URL (default: a private one per run)");
  c->add_flag("--no-noise", m.no_noise, "plant noise off");
  c->add_option("--plant-jitter-ms", m.plant_jitter_ms,
                "with --free-running: the plant's tick times off by up to this much");
  c->add_option_function<std::vector<std::string>>(
       "--on",
       [&m](const std::vector<std::string>& v) {
         for (const std::string& kv : v) {
           const auto eq = kv.find('=');
           if (eq == std::string::npos || eq == 0 || eq + 1 == kv.size())
             throw CLI::ValidationError("--on", "\"" + kv + "\" is not PROCESS=HOST");
           m.hosts[kv.substr(0, eq)] = kv.substr(eq + 1);
         }
       },
       "multi-host (needs FRALAB_NETWORK=1): PROCESS=HOST runs plant, recorder, acquire, "
       "analyze or identify through the deputy HOST (fralab-deputy --name HOST); repeatable")
      ->delimiter(',');
  c->add_option("--deputy-url", m.deputy_url, "the deputies' LCM URL (multi-host)");
  c->add_flag("!--no-progress", m.progress, "no progress line (it is shown on a terminal only)");
  c->add_option_function<std::string>(
       "--analysers", [&m](const std::string& w) { m.analysers = AnalyserGrouping::parse(w); },
       "how the live analysers share the pairs (each process decodes a block once for its "
       "pairs): input (one process per input), pair (each pair alone, an input's command pairs "
       "together) or N (N pairs each)")
      ->default_str("input");
  c->add_option("--stall-timeout", m.stall_timeout_s,
                "seconds a stream may stand still (retransmitted) before the run fails")
      ->capture_default_str();
}

void print_measure(const MeasureResult& r, const std::string& out) {
  std::printf(
      "fralab: %zu pairs measured; engine time %.0f s (%.2f h), wall time %.1f s (%.0fx); tape "
      "%s/tape.lcmlog (%lld blocks); frd in %s/frd\n",
      r.pairs.size(), r.engine_time_s, r.engine_time_s / 3600, r.wall_time_s,
      r.engine_time_s / std::max(r.wall_time_s, 1e-9), out.c_str(), (long long)r.tape_blocks,
      out.c_str());
}

void throw_if_partial(const std::vector<std::string>& partial) {
  std::string all;
  for (const std::string& p : partial) all += (all.empty() ? "" : "\n") + p;
  if (!all.empty()) throw PartialRun(all);
}

void add_operating_point_flag(CLI::App* c, std::string& op) {
  c->add_option("--operating-point", op,
                "X or KEY=X: the engine and simulation SETs (an embedded family such as j85, a "
                "folder or comma list of models) at that operating point, interpolated between "
                "their models; the same as --engine SET@X");
}

std::string at_operating_point(const std::string& spec, const std::string& op) {
  return op.empty() || spec.empty() ? spec : spec + "@" + op;
}

void add_measure_command(CLI::App& app) {
  auto mo = std::make_shared<MeasureOptions>();
  auto* c = app.add_subcommand("measure", "plant, acquisition, analysers: tape and frd files");
  auto* engine = c->add_option("--engine", mo->engine, "engine model file or embedded name");
  auto* out = c->add_option("--out", mo->out);
  add_measure_flags(c, *mo);
  auto op = std::make_shared<std::string>();
  add_operating_point_flag(c, *op);
  auto resume = std::make_shared<std::string>();
  c->add_option("--resume", *resume,
                "continue the interrupted or failed run in DIR from its first incomplete step "
                "(every other option comes from DIR/run.json)")
      ->excludes(engine)
      ->excludes(out);
  c->callback([mo, engine, out, resume, op] {
    mo->engine = at_operating_point(mo->engine, *op);
    if (!resume->empty()) {
      mo->resume = true;
      mo->out = *resume;
    } else {
      if (engine->count() == 0) throw CLI::RequiredError("--engine");
      if (out->count() == 0) throw CLI::RequiredError("--out");
    }
    const MeasureResult r = measure(*mo);
    print_measure(r, mo->out);
    if (r.partial()) throw_if_partial({partial_run_message(r, mo->out)});
  });
}

}  // namespace fralab
