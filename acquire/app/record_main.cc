// fralab-record: the lab's tape recorder, inside the flow control. Writes every message of the LCM
// URL to a standard LCM log (what lcm-logplayer replays) and acknowledges each tape block once it
// is on disk (FRALAB_ACK, consumer "recorder"). Runs until SIGINT or SIGTERM.
#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <iostream>

#include "fralab/core/error.h"
#include "fralab/lcm/lab_lcm.h"
#include "recorder_node.h"

using namespace fralab;

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-record: the tape recorder inside the flow control"};
  std::string url, ctl_url, run_id, out, name = "recorder";
  app.add_option("--lcm-url", url, "LCM URL");
  app.add_option("--control-url", ctl_url,
                 "LCM URL for acknowledgements (default: --lcm-url with port + 1)");
  app.add_option("--run-id", run_id, "acknowledge only this run's blocks");
  app.add_option("--out", out, "the tape (LCM log) to write")->required();
  app.add_option("--name", name, "consumer name for flow control")->capture_default_str();
  bool append = false;
  int64_t first_block = 0, first_status = 0;
  app.add_flag("--append", append, "resume: add to the existing tape");
  app.add_option("--first-block", first_block, "resume: the first tape block expected")
      ->capture_default_str();
  app.add_option("--first-status", first_status, "resume: the first status event expected")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    LabLcm io(url, ctl_url);
    lcm::LCM& lcm = io.data;
    lcm::LCM& ctl = io.control;
    RecorderNode rec(lcm, ctl, out, run_id, name, append, first_block, first_status);
    auto last_ready = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    while (!g_stop) {
      if (!rec.started() &&
          std::chrono::steady_clock::now() - last_ready > std::chrono::milliseconds(100)) {
        rec.announce_ready();
        last_ready = std::chrono::steady_clock::now();
      }
      lcm.handleTimeout(100);
      if (!rec.error().empty()) throw InputError(rec.error());
    }
    // Stopped: what is already queued (the last blocks, an abort) still goes on the tape.
    for (int i = 0; i < 20 && lcm.handleTimeout(10) > 0;) ++i;
    if (!rec.error().empty()) throw InputError(rec.error());
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-record: " << e.what() << "\n";
    return 1;
  }
}
