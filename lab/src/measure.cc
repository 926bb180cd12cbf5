#include "fralab/lab/measure.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <map>
#include <thread>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/acquire/model_info.h"
#include "fralab/core/frd.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/text.h"
#include "fralab/identify/fit_io.h"
#include "fralab/lab/auto_campaign.h"
#include "fralab/lab/deputy.h"
#include "fralab/lab/progress.h"
#include "fralab/lab/resume.h"
#include "fralab/lab/run_lock.h"
#include "fralab/lab/supervisor.h"
#include "fralab/lcm_io.h"
#include "fralab/plant/embedded_models.h"
#include "tape_analysis.h"

namespace fralab {

namespace fs = std::filesystem;

std::vector<std::string> pairs_for_input(const std::string& x,
                                         const std::vector<std::string>& outs) {
  std::vector<std::string> p;
  for (const auto& o : outs) p.push_back(x + ":" + o);
  p.push_back("u_" + x + ":" + x);
  for (const auto& o : outs) p.push_back("u_" + x + ":" + o);
  return p;
}

namespace {

// Reads the tape back as the recorder writes it (each call reads only what was added since the
// last): every tape block and status event of the run, without gaps (retransmitted copies and
// their order do not matter), and the final "done" status. The command blocks are on the tape
// too, but not required: every tape block echoes its commands.
class TapeCheck {
 public:
  TapeCheck(std::string path, std::string run_id)
      : path_(std::move(path)), run_id_(std::move(run_id)) {}

  // The number of tape blocks; -1 while incomplete (recorder still writing), -2 when a block was
  // lost.
  int64_t update(std::string* problem) {
    try {
      follow_tape_file(path_, &offset_, [&](const TapeEvent& ev) { take(ev); });
    } catch (const InputError& e) {
      *problem = e.what();
      return -1;  // cannot open it (yet): try again
    }
    if (!bad_.empty()) {  // a whole event that does not decode: no retry mends that
      *problem = bad_;
      return -2;
    }
    if (!final_tape_ || !done_) {
      *problem = "the tape does not yet hold the final block and the done status (read to byte " +
                 std::to_string(offset_) + ")";
      return -1;
    }
    for (auto& [kind, v] : seqs_) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());  // retransmitted copies
      for (size_t i = 0; i < v.size(); ++i) {
        if (v[i] != int64_t(i)) {
          *problem = "the tape lost " + kind + (kind == "status" ? " event" : " block") + " seq " +
                     std::to_string(i);
          return -2;
        }
      }
    }
    return int64_t(seqs_["tape"].size());
  }

 private:
  void take(const TapeEvent& ev) {
    if (!bad_.empty()) return;
    try {
      decode(ev);
    } catch (const InputError& e) {
      bad_ = "event " + std::to_string(ev.eventnum) + ": " + e.what();
    }
  }
  void decode(const TapeEvent& ev) {
    lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
    if (ev.channel == kTapeChannel) {
      Block m;
      try {
        m = decode_tape_block(&rb, ev.channel);
      } catch (const CorruptBlock&) {  // a later copy (retransmitted) may be whole
        return;
      }
      if (m.run_id == run_id_ && m.seq >= 0) {  // seq -1: an aborted run's last block
        seqs_["tape"].push_back(m.seq);
        final_tape_ |= m.final_block;
      }
    } else if (ev.channel == kStatusChannel) {
      auto m = decode_checked<excitation_status_t>(&rb, ev.channel);
      if (m.run_id != run_id_) return;
      if (m.seq >= 0) seqs_["status"].push_back(m.seq);
      done_ |= from_msg(m).state == RunState::kDone;
    }
  }

  std::string path_, run_id_;
  int64_t offset_ = 0;
  std::map<std::string, std::vector<int64_t>> seqs_;
  bool done_ = false, final_tape_ = false;
  std::string bad_;
};

}  // namespace

MeasurementChain emulator_chain(const Model& m, double sample_rate_hz) {
  MeasurementChain c;
  c.sample_rate_hz = sample_rate_hz;
  c.hold = MeasurementChain::Hold::kFirstOrder;
  for (const auto& in : m.inputs)
    if (!in.nonlinearity.empty()) c.reheld_inputs.push_back(in.name);
  return c;
}

namespace {

// The run's record, DIR/run.json: written when the run starts (state "running", with what is
// needed to resume it), and again when it ends ("complete", "failed" with the reason,
// "interrupted").
void save_run(const std::string& out, const Json& run) {
  json_save_file(MeasureDir(out).run_json(), run);
}

// The options of the run recorded in DIR/run.json (--resume DIR).
MeasureOptions options_from_run(const std::string& dir, const Json& run) {
  MeasureOptions o;
  o.out = dir;
  o.resume = true;
  try {
    const Json& opt = run.at("options");
    o.engine = MeasureDir(dir).engine();
    o.seed = opt.at("seed").get<uint64_t>();
    o.no_noise = opt.at("no_noise").get<bool>();
    o.fit_delay = opt.at("fit_delay").get<std::string>();
    o.timeout_s = opt.value("timeout_s", o.timeout_s);
    o.stall_timeout_s = opt.value("stall_timeout_s", o.stall_timeout_s);
    o.hosts = opt.value("hosts", o.hosts);
    o.deputy_url = opt.value("deputy_url", o.deputy_url);
    std::vector<std::string> flags = opt.at("acquire_flags").get<std::vector<std::string>>();
    CLI::App app;
    add_acquire_flags(&app, o.acquire);
    std::reverse(flags.begin(), flags.end());  // CLI11 parses a vector from its back
    app.parse(flags);
  } catch (const std::exception& e) {
    throw InputError(dir + "/run.json: cannot resume from it: " + e.what());
  }
  return o;
}

}  // namespace

std::string save_curves_and_fit(std::vector<Frd>& curves, const std::string& dir,
                                const std::string& fit_delay, const std::string& title,
                                double timeout_s) {
  std::sort(curves.begin(), curves.end(),
            [](const Frd& a, const Frd& b) { return a.pair < b.pair; });
  const MeasureDir md(dir);
  fs::create_directories(md.frd_dir());
  fs::create_directories(md.logs_dir());
  for (const Frd& f : curves) save_frd(md.frd(f.pair), f);
  FitOptions fo;
  parse_delay_option(fit_delay, &fo);  // a bad --delay is the caller's error, not a failed fit
  std::vector<std::string> args = {module_path("fralab-identify"),
                                   "--from-frd",
                                   dir,
                                   "--out",
                                   dir,
                                   "--delay",
                                   fit_delay,
                                   "--title",
                                   title};
  for (const Frd& f : curves) args.insert(args.end(), {"--pair", f.pair});
  Supervisor sup;
  sup.start({"identify", args, md.log("identify"), /*host=*/""});
  try {
    sup.wait_for({"identify"}, timeout_s);
  } catch (const Interrupted&) {
    throw;
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string partial_run_message(const MeasureResult& r, const std::string& dir) {
  return dir + ": partial run: everything was measured (tape and frd files complete), but " +
         r.failed_step + " failed: " + r.failure + "; fit again with `fralab measure --resume " +
         dir + "`";
}

void record_fit_outcome(Json& run, MeasureResult& r, const std::string& fit_failure,
                        const std::string& dir) {
  run.erase("reason");
  if (fit_failure.empty()) {
    run["state"] = "complete";
    run.erase("failed_step");
    r.failed_step.clear(), r.failure.clear();
    return;
  }
  run["state"] = "partial";
  run["failed_step"] = {{"step", "identify"}, {"error", fit_failure}};
  r.failed_step = "identify";
  r.failure = fit_failure;
}

MeasureResult run_measure(const MeasureOptions& given) {
  if (given.out.empty()) throw InputError("--out DIR is required");
  if (given.auto_campaign) {
    MeasureOptions o = given;
    o.auto_campaign = false;  // its runs are plain ones
    return run_auto_campaign(o).measure;
  }
  const MeasureDir given_dir(given.out);
  if (given.resume && !fs::exists(given_dir.run_json())) {
    if (fs::exists(given_dir.multisine().run_json()))
      throw InputError(given.out +
                       ": an auto campaign that did not end resumes its runs one by one: "
                       "`fralab measure --resume " +
                       given.out + "/multisine` (or /sine)");
    throw InputError(given.out +
                     "/run.json: no such file: --resume needs the folder of a run started by "
                     "`fralab measure`");
  }
  if (given.resume && json_load_file(given_dir.run_json()).value("excitation", "") == "auto")
    return resume_auto_campaign(given.out);
  // The folder is this run's until it ends: a second run or a resume on it is refused.
  const RunLock lock(given.out, given.resume ? "fralab measure --resume" : "fralab measure");
  Json run;
  MeasureOptions o = given;
  if (given.resume) {
    run = json_load_file(given_dir.run_json());
    if (run.value("state", "") == "complete")
      throw InputError(given.out + ": the run is complete; there is nothing to resume");
    o = options_from_run(given.out, run);
  }
  Model model = load_model_or_embedded(o.engine);
  o.acquire.validate();
  std::vector<int> excite = select_inputs(model, o.acquire.inputs);
  const MeasureDir dir(o.out);
  fs::create_directories(dir.frd_dir());
  fs::create_directories(dir.logs_dir());
  const std::string engine_file = dir.engine();
  if (!o.resume) save_model(engine_file, model);  // the exact model measured, beside its tape

  MeasureResult r;
  const uint64_t salt = uint64_t(getpid()) * 1000003u ^
                        uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
  for (const auto& [kind, host] : o.hosts)
    if (kind != "plant" && kind != "recorder" && kind != "acquire" && kind != "analyze" &&
        kind != "identify")
      throw InputError("--on " + kind + "=" + host +
                       ": no such process (plant, recorder, acquire, analyze, identify)");
  std::string url = o.lcm_url.empty() ? private_lcm_url(salt) : o.lcm_url;
  if (!o.hosts.empty() && o.lcm_url.empty()) url.replace(url.find("ttl=0"), 5, "ttl=1");
  url = resolve_lcm_url(url);  // ttl=1 needs FRALAB_NETWORK=1
  r.run_id =
      o.resume ? run.at("run_id").get<std::string>() : "run-" + std::to_string(salt % 1000000007u);
  const std::string tape = dir.tape();
  std::string inputs_csv;
  for (int i : excite) inputs_csv += (inputs_csv.empty() ? "" : ",") + model.inputs[i].name;
  AcquireOptions ao = o.acquire;
  ao.inputs = inputs_csv;
  // The lab's measurement chain: recorded in run.json and, through the acquisition, on the tape.
  const Json chain = chain_to_json(emulator_chain(model, ao.sample_rate_hz));
  std::vector<std::string> outs;
  for (const auto& out : model.outputs) outs.push_back(out.name);
  for (int i : excite) {
    auto pairs = pairs_for_input(model.inputs[i].name, outs);
    r.pairs.insert(r.pairs.end(), pairs.begin(), pairs.end());
  }

  ResumePoint rp;
  if (o.resume) {
    const int64_t cut = cut_tape_to_whole_events(tape);
    if (cut > 0)
      std::cerr << "fralab: " << tape << ": cut " << cut
                << " bytes of a partly written last event\n";
    if (ao.adaptive.enabled()) {
      rp = plan_adaptive_resume(tape, r.run_id, model, ao);  // sets the decisions taken
    } else {
      const auto camp = make_campaign(model, ao, r.run_id);
      rp = plan_resume(tape, r.run_id, *camp, ao.block);
    }
    std::cerr << "fralab: resuming run " << r.run_id << ": " << rp.blocks_on_tape
              << " tape blocks on the tape; "
              << (rp.complete ? "every block is there"
                              : "starting again at step " + std::to_string(rp.first_step) +
                                    " (command block " + std::to_string(rp.first_block) + ")")
              << "\n";
    run["resumed"] = run.value("resumed", 0) + 1;
  } else {
    fs::remove(tape);
    run = Json{{"format", "fralab-run/1"},
               {"run_id", r.run_id},
               {"engine", model.name},
               {"inputs", inputs_csv},
               {"pairs", r.pairs},
               {"options",
                {{"seed", o.seed},
                 {"no_noise", o.no_noise},
                 {"fit_delay", o.fit_delay},
                 {"timeout_s", o.timeout_s},
                 {"stall_timeout_s", o.stall_timeout_s},
                 {"hosts", o.hosts},
                 {"deputy_url", o.deputy_url},
                 {"acquire_flags", acquire_flags(ao)}}},
               {"measurement_chain", chain}};
  }
  run["lcm_url"] = url;
  run["state"] = "running";
  save_run(o.out, run);
  auto log = [&](const std::string& n) { return dir.log(n); };

  Supervisor::catch_stop_signals();
  // Deputies for the processes on other hosts (declared before the supervisor: it uses them until
  // its end).
  std::unique_ptr<lcm::LCM> deputy_lcm;
  std::unique_ptr<DeputyClient> deputies;
  if (!o.hosts.empty()) {
    const std::string durl =
        resolve_lcm_url(o.deputy_url.empty() ? kDefaultDeputyUrl : o.deputy_url);
    deputy_lcm = std::make_unique<lcm::LCM>(durl);
    require_lcm(*deputy_lcm, "the deputies' LCM URL", durl);
    deputies = std::make_unique<DeputyClient>(*deputy_lcm, r.run_id);
    for (const auto& [kind, host] : o.hosts) deputies->wait_for_deputy(host, 10);
  }
  auto host_of = [&](const std::string& kind) {
    auto it = o.hosts.find(kind);
    return it == o.hosts.end() ? std::string() : it->second;
  };
  Supervisor sup;
  sup.set_remote(deputies.get());
  sup.set_stop_first(
      {"acquire"});         // the excitation stops first, actuators to their operating point
  std::string fit_failure;  // the identifier's, when it failed after everything was measured
  try {
    if (!rp.complete) {
      // The recorder: inside the flow control (a consumer the acquisition waits for), so a busy
      // machine slows the run instead of losing tape blocks.
      std::vector<std::string> rec = {
          module_path("fralab-record"), "--lcm-url", url, "--run-id", r.run_id, "--out", tape};
      if (o.resume)
        for (const std::string& a :
             {std::string("--append"), std::string("--first-block"), std::to_string(rp.first_block),
              std::string("--first-status"), std::to_string(rp.first_status)})
          rec.push_back(a);
      sup.start({"recorder", rec, log("recorder"), host_of("recorder")});

      std::vector<std::string> plant_args = {module_path("fralab-plant"),
                                             "--model",
                                             engine_file,
                                             "--lcm-url",
                                             url,
                                             "--seed",
                                             std::to_string(o.seed),
                                             "--run-id",
                                             r.run_id,
                                             "--sample-rate",
                                             lossless(o.acquire.sample_rate_hz)};
      if (o.no_noise) plant_args.push_back("--no-noise");
      if (o.acquire.free_running)  // on its own clock, a tape block per command block's length
        plant_args.insert(plant_args.end(), {"--free-running", "--speed", lossless(o.acquire.speed),
                                             "--tick", std::to_string(o.acquire.block),
                                             "--jitter-ms", lossless(o.plant_jitter_ms)});
      if (o.resume) {
        plant_args.insert(plant_args.end(),
                          {"--replay", tape, "--replay-blocks", std::to_string(rp.first_block)});
      }
      sup.start({"plant", plant_args, log("plant"), host_of("plant")});

      std::vector<std::string> consumers = {"plant", "recorder"}, waits = {"plant"};
      // A fresh run: the live analysers (one process per position-relative pair, one for the
      // command-relative ones) and the identifier. A resumed run analyses the whole tape at the
      // end instead.
      if (!o.resume) {
        for (int i : excite) {
          auto pairs = pairs_for_input(model.inputs[i].name, outs);
          std::vector<std::vector<std::string>> groups;
          for (size_t k = 0; k <= outs.size(); ++k) groups.push_back({pairs[k]});
          groups.push_back(std::vector<std::string>(pairs.begin() + outs.size() + 1, pairs.end()));
          for (const auto& g : groups) {
            std::string name =
                "analyze-" + pair_file_stem(g.front()) + (g.size() > 1 ? "-cmd" : "");
            // Analysers run at lower priority: they are flow-controlled like the plant and
            // recorder.
            std::vector<std::string> args = {
                "nice",      "-n", "5",        module_path("fralab-analyze"),
                "--lcm-url", url,  "--run-id", r.run_id,
                "--name",    name, "--out",    o.out,
                "--linger",  "30"};
            for (const auto& p : g) {
              args.push_back("--pair");
              args.push_back(p);
            }
            sup.start({name, args, log(name), host_of("analyze")});
            consumers.push_back(name);
            waits.push_back(name);
          }
        }
        sup.start({"identify",
                   {module_path("fralab-identify"), "--lcm-url", url, "--run-id", r.run_id,
                    "--expect", std::to_string(r.pairs.size()), "--out", o.out, "--delay",
                    o.fit_delay, "--title", model.name + ": measured transfer matrix"},
                   log("identify"),
                   host_of("identify"),
                   /*essential=*/false});
      }
      std::string consumers_csv;
      for (const auto& c : consumers) consumers_csv += (consumers_csv.empty() ? "" : ",") + c;
      std::vector<std::string> acq = {module_path("fralab-acquire"),
                                      "--engine",
                                      engine_file,
                                      "--lcm-url",
                                      url,
                                      "--run-id",
                                      r.run_id,
                                      "--consumers",
                                      consumers_csv,
                                      "--stall-timeout",
                                      lossless(o.stall_timeout_s),
                                      "--first-block",
                                      std::to_string(rp.first_block),
                                      "--first-status",
                                      std::to_string(rp.first_status),
                                      "--summary",
                                      dir.acquire_summary(),
                                      "--chain",
                                      chain.dump()};
      for (const std::string& f : acquire_flags(ao)) acq.push_back(f);
      const auto t0 = std::chrono::steady_clock::now();
      // The progress line, on a terminal only: it listens to the run's status events and
      // retransmission requests.
      ProgressLine progress;
      std::unique_ptr<lcm::LCM> watch;
      std::string shown;
      auto since = [&](std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
      };
      auto last_draw = t0;
      struct Listener {
        ProgressLine* p;
        std::string run_id;
        void on_status(const lcm::ReceiveBuffer* rb, const std::string& ch) {
          const auto m = decode_checked<excitation_status_t>(rb, ch);
          if (m.run_id == run_id) p->on_status(from_msg(m));
        }
        void on_flow(const lcm::ReceiveBuffer* rb, const std::string& ch) {
          const auto f = decode_checked<flow_t>(rb, ch);
          if (f.run_id == run_id && f.kind == "resend") p->on_resent(f.to_seq - f.from_seq + 1);
        }
      } listener{&progress, r.run_id};
      if (isatty(STDERR_FILENO) && o.progress) {
        watch = std::make_unique<lcm::LCM>(url);
        if (watch->good()) {
          watch->subscribe(kStatusChannel, &Listener::on_status, &listener);
          watch->subscribe(kFlowChannel, &Listener::on_flow, &listener);
        } else {
          watch.reset();
        }
      }
      auto draw = [&] {
        if (!watch) return;
        try {
          while (watch->handleTimeout(0) > 0) {
          }
        } catch (const InputError&) {  // a malformed status: the line is only a face
        }
        if (since(last_draw) < 0.2) return;
        last_draw = std::chrono::steady_clock::now();
        const std::string l = progress.line(since(t0));
        if (l != shown && !l.empty()) std::cerr << "\r" << l << "\033[K" << std::flush;
        shown = l;
      };
      sup.start({"acquire", acq, log("acquire"), host_of("acquire")});
      waits.push_back("acquire");
      try {
        sup.wait_for(waits, o.timeout_s, draw);
      } catch (...) {
        if (!shown.empty()) std::cerr << "\n";
        throw;
      }
      if (!shown.empty()) std::cerr << "\r" << progress.line(since(t0)) << "\033[K\n";
      r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    const auto t_fit = std::chrono::steady_clock::now();
    if (!o.resume) {
      try {  // a failed fit leaves the measurement whole: the run ends partial
        sup.wait_for({"identify"}, o.timeout_s);
      } catch (const Interrupted&) {
        throw;
      } catch (const InputError& e) {
        fit_failure = e.what();
      }
    }

    // The recorder acknowledged every tape block once on disk; the tape is read back and checked
    // (every tape block and status event, the done status) before the recorder is stopped.
    std::string problem;
    int64_t n = -1;
    TapeCheck check(tape, r.run_id);
    for (int i = 0; i < 200 && n < 0; ++i) {
      n = check.update(&problem);
      if (n == -1) std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (n == -2) break;
    }
    sup.stop("recorder", SIGINT, 5.0);
    if (n < 0) throw InputError(tape + ": " + problem);
    r.tape_blocks = n;
    if (o.resume) {
      // The whole tape, analysed as the live analysers would (tape = live), then fitted as the
      // live identifier would (the curves in pair order).
      std::vector<Frd> curves = analyze_tape_file(tape, r.pairs, {});
      fit_failure = save_curves_and_fit(curves, o.out, o.fit_delay,
                                        model.name + ": measured transfer matrix", o.timeout_s);
    }
    r.fit_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_fit).count();
  } catch (const Interrupted& e) {
    sup.stop_all();
    run["state"] = "interrupted";
    run["reason"] = e.what();
    save_run(o.out, run);
    throw InputError(std::string(e.what()) +
                     ": the excitation was stopped first, then every "
                     "process; resume with `fralab measure --resume " +
                     o.out + "`");
  } catch (const std::exception& e) {
    sup.stop_all();
    run["state"] = "failed";
    run["reason"] = e.what();
    save_run(o.out, run);
    throw InputError(std::string(e.what()) + " (everything measured is kept in " + o.out +
                     "; resume with `fralab measure --resume " + o.out + "`)");
  }
  const auto camp = make_campaign(model, ao, r.run_id);
  double engine_total = double(camp->total_samples()) / o.acquire.sample_rate_hz;
  if (fs::exists(dir.acquire_summary())) {
    Json acq_summary = json_load_file(dir.acquire_summary());
    // The adaptive campaign grew while running: its length is the summary's.
    if (ao.adaptive.enabled())
      engine_total = acq_summary.at("samples").get<double>() / o.acquire.sample_rate_hz;
    run["retransmissions"] = acq_summary.value("retransmissions", 0);
    run["items_retransmitted"] = acq_summary.value("items_retransmitted", 0);
  }
  r.engine_time_s = engine_total;
  if (ao.adaptive.enabled()) {  // each step as decided, from the curves (a resumed run's too)
    std::vector<Frd> curves;
    for (const std::string& p : r.pairs)
      if (const std::string f = dir.frd(p); fs::exists(f)) curves.push_back(load_frd(f));
    const auto& adaptive = dynamic_cast<const AdaptiveSineCampaign&>(*camp);
    std::vector<int> limits;
    for (int g = 0; g < adaptive.n_steps(); ++g) limits.push_back(adaptive.limit(g));
    run["adaptive"] = adaptive_steps_json(adaptive_steps(curves, ao.adaptive.sigma_target, limits));
  }
  record_fit_outcome(run, r, fit_failure, o.out);
  run["engine_time_s"] = r.engine_time_s;
  run["wall_time_s"] = r.wall_time_s;
  run["speedup"] = r.engine_time_s / std::max(r.wall_time_s, 1e-9);
  run["tape_blocks"] = r.tape_blocks;
  run["fit_time_s"] = r.fit_time_s;
  save_run(o.out, run);
  return r;
}

}  // namespace fralab
