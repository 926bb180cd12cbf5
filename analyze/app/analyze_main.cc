// fralab-analyze: live two-channel servoanalyser, one process per pair (or several pairs).
// Subscribes to tape blocks and excitation status, publishes each pair's curve point by point
// (FRALAB_FRD), acknowledges every tape block (FRALAB_ACK, for the acquisition's flow control), and
// writes DIR/frd/<E1>_<E2>.json when the run is done. `--log TAPE` reads a tape file directly
// instead.
#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <iostream>

#include "analyzer_node.h"
#include "fralab/core/measure_dir.h"
#include "fralab/lcm/lab_lcm.h"

using namespace fralab;

namespace {

void write_frds(const std::vector<Frd>& frds, const std::string& out) {
  const MeasureDir dir(out);
  std::filesystem::create_directories(dir.frd_dir());
  for (const Frd& f : frds) save_frd(dir.frd(f.pair), f);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-analyze: two-channel Fourier-filter servoanalyser"};
  std::vector<std::string> pairs;
  std::string url, ctl_url, out, name, run_id, log, input;
  AnalyzerOptions opt;
  app.add_option("--pair", pairs, "pair E1:E2 (response E2/E1); repeatable")->required();
  app.add_option("--lcm-url", url, "LCM URL");
  app.add_option("--control-url", ctl_url,
                 "LCM URL for acknowledgements (default: --lcm-url with port + 1)");
  app.add_option("--out", out, "write OUT/frd/<E1>_<E2>.json when done");
  app.add_option("--name", name, "consumer name for flow control (default: first pair)");
  app.add_option("--run-id", run_id, "only this run");
  app.add_option("--input", opt.input, "only steps exciting this input");
  double linger = 0, handover = 20;
  app.add_option("--linger", linger,
                 "seconds to wait, once the analysis is done, for the acquisition's close (the lab "
                 "passes it: a retransmitted block may still need acknowledging); 0: exit when "
                 "done (following a replay)")
      ->capture_default_str();
  app.add_option("--handover", handover,
                 "seconds to republish the complete curves until an identifier that announced "
                 "itself acknowledges each")
      ->capture_default_str();
  app.add_option("--log", log, "tape mode: read this LCM log file directly (no LCM traffic)");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!log.empty()) {
      auto frds = analyze_tape_file(log, pairs, opt);
      if (!out.empty()) write_frds(frds, out);
      for (const Frd& f : frds) std::cout << frd_to_json(f).dump() << "\n";
      return 0;
    }
    LabLcm io(url, ctl_url);
    lcm::LCM& lcm = io.data;
    lcm::LCM& ctl = io.control;
    AnalyzerNode live(lcm, ctl, pairs, opt, name, run_id);
    using Clock = std::chrono::steady_clock;
    auto last_ready = Clock::now() - std::chrono::seconds(1);
    auto since = [](Clock::time_point t) {
      return std::chrono::duration<double>(Clock::now() - t).count();
    };
    // Runs until the run is analysed and the acquisition says every consumer holds everything
    // (until then a retransmitted block may still need acknowledging), or `linger` s after the
    // analysis is done without the close (the acquisition gone, or none: a replay).
    Clock::time_point done_at{};
    while (!(live.done() && live.closed())) {
      if (!live.started() && since(last_ready) > 0.1) {
        live.announce_ready();
        last_ready = Clock::now();
      }
      lcm.handleTimeout(100);  // the control URL is only published to
      if (!live.error().empty()) throw InputError(live.error());
      if (live.done() && done_at == Clock::time_point{}) done_at = Clock::now();
      if (live.done() && since(done_at) > linger) break;
    }
    const std::vector<Frd> frds = live.finish();
    if (!out.empty()) write_frds(frds, out);
    // Hands the complete curves to the identifier, republishing until it has acknowledged each.
    const auto t_hand = Clock::now();
    while (live.identifier_heard() && !live.curves_taken() && since(t_hand) < handover) {
      lcm.handleTimeout(200);
      live.republish_untaken();
    }
    if (live.identifier_heard() && !live.curves_taken())
      std::cerr << "fralab-analyze: warning: the identifier did not acknowledge every curve within "
                << handover << " s (the files are in " << (out.empty() ? "(no --out)" : out)
                << "/frd)\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-analyze: " << e.what() << "\n";
    return 1;
  }
}
