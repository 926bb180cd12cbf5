#include "fralab/lab/measure.h"

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <map>
#include <thread>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/acquire/model_info.h"
#include "fralab/core/frd.h"
#include "fralab/core/text.h"
#include "fralab/lab/supervisor.h"
#include "fralab/lcm_io.h"
#include "fralab/plant/embedded_models.h"

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
      auto m = decode_checked<tape_block_t>(&rb, ev.channel);
      if (m.run_id == run_id_) {
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

MeasureResult run_measure(const MeasureOptions& o) {
  if (o.out.empty()) throw InputError("--out DIR is required");
  Model model = load_model_or_embedded(o.engine);
  o.acquire.validate();
  std::vector<int> excite = select_inputs(model, o.acquire.inputs);
  fs::create_directories(o.out + "/frd");
  fs::create_directories(o.out + "/logs");
  const std::string engine_file = o.out + "/engine.json";
  save_model(engine_file, model);  // the exact model measured, beside its tape

  MeasureResult r;
  const uint64_t salt = uint64_t(getpid()) * 1000003u ^
                        uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
  const std::string url = o.lcm_url.empty() ? private_lcm_url(salt) : resolve_lcm_url(o.lcm_url);
  r.run_id = "run-" + std::to_string(salt % 1000000007u);
  const std::string tape = o.out + "/tape.lcmlog";
  fs::remove(tape);
  auto log = [&](const std::string& n) { return o.out + "/logs/" + n + ".log"; };

  Supervisor sup;
  // The recorder: inside the flow control (a consumer the acquisition waits for), so a busy machine
  // slows the run instead of losing tape blocks.
  sup.start({"recorder",
             {module_path("fralab-record"), "--lcm-url", url, "--run-id", r.run_id, "--out", tape},
             log("recorder")});

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
  sup.start({"plant", plant_args, log("plant")});

  std::vector<std::string> outs;
  for (const auto& out : model.outputs) outs.push_back(out.name);
  std::vector<std::string> consumers = {"plant", "recorder"}, waits = {"plant"};
  for (int i : excite) {
    const std::string x = model.inputs[i].name;
    auto pairs = pairs_for_input(x, outs);
    r.pairs.insert(r.pairs.end(), pairs.begin(), pairs.end());
    // One process per position-relative pair, one for the command-relative ones.
    std::vector<std::vector<std::string>> groups;
    for (size_t k = 0; k <= outs.size(); ++k) groups.push_back({pairs[k]});
    groups.push_back(std::vector<std::string>(pairs.begin() + outs.size() + 1, pairs.end()));
    for (const auto& g : groups) {
      std::string name = "analyze-" + pair_file_stem(g.front()) + (g.size() > 1 ? "-cmd" : "");
      // Analysers run at lower priority: they are flow-controlled like the plant and recorder.
      std::vector<std::string> args = {"nice",      "-n", "5",        module_path("fralab-analyze"),
                                       "--lcm-url", url,  "--run-id", r.run_id,
                                       "--name",    name, "--out",    o.out,
                                       "--linger",  "30"};
      for (const auto& p : g) {
        args.push_back("--pair");
        args.push_back(p);
      }
      sup.start({name, args, log(name)});
      consumers.push_back(name);
      waits.push_back(name);
    }
  }
  // The identifier: fits every curve once the analysers publish them complete.
  sup.start({"identify",
             {module_path("fralab-identify"), "--lcm-url", url, "--run-id", r.run_id, "--expect",
              std::to_string(r.pairs.size()), "--out", o.out, "--delay", o.fit_delay, "--title",
              model.name + ": measured transfer matrix"},
             log("identify")});
  std::string consumers_csv;
  for (const auto& c : consumers) consumers_csv += (consumers_csv.empty() ? "" : ",") + c;
  std::string inputs_csv;
  for (int i : excite) inputs_csv += (inputs_csv.empty() ? "" : ",") + model.inputs[i].name;
  AcquireOptions ao = o.acquire;
  ao.inputs = inputs_csv;
  std::vector<std::string> acq = {module_path("fralab-acquire"),
                                  "--engine",
                                  engine_file,
                                  "--lcm-url",
                                  url,
                                  "--run-id",
                                  r.run_id,
                                  "--consumers",
                                  consumers_csv,
                                  "--summary",
                                  o.out + "/acquire.json"};
  for (const std::string& f : acquire_flags(ao)) acq.push_back(f);
  const auto t0 = std::chrono::steady_clock::now();
  sup.start({"acquire", acq, log("acquire")});
  waits.push_back("acquire");
  sup.wait_for(waits, o.timeout_s);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto t_fit = std::chrono::steady_clock::now();
  sup.wait_for({"identify"}, o.timeout_s);
  r.fit_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_fit).count();

  // The recorder acknowledged every tape block once on disk; the tape is read back and checked
  // (every command and tape block, the done status) before the recorder is stopped.
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
  Json acq_summary = json_load_file(o.out + "/acquire.json");
  r.engine_time_s = acq_summary.value("engine_time_s", 0.0);
  Json summary{
      {"run_id", r.run_id},
      {"engine", model.name},
      {"lcm_url", url},
      {"inputs", inputs_csv},
      {"pairs", r.pairs},
      {"engine_time_s", r.engine_time_s},
      {"wall_time_s", r.wall_time_s},
      {"speedup", r.engine_time_s / std::max(r.wall_time_s, 1e-9)},
      {"tape_blocks", n},
      {"fit_time_s", r.fit_time_s},
      {"measurement_chain", chain_to_json(emulator_chain(model, o.acquire.sample_rate_hz))}};
  json_save_file(o.out + "/run.json", summary);
  return r;
}

}  // namespace fralab
