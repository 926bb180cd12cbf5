// fralab-analyze: live two-channel servoanalyser, one process per pair (or several pairs).
// Subscribes to tape blocks and excitation status, publishes each pair's curve point by point
// (FRALAB_FRD), acknowledges every tape block (FRALAB_ACK, for the acquisition's flow control), and
// writes DIR/frd/<E1>_<E2>.json when the run is done. `--log TAPE` reads a tape file directly
// instead.
#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <iostream>

#include "tape_analysis.h"

using namespace fralab;

namespace {

struct Live {
  TapeFeeder* feeder;
  lcm::LCM* lcm;
  lcm::LCM* ctl;
  std::string name;
  bool started = false;
  int64_t frd_seq = 0;
  std::string error;

  void on_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (!error.empty()) return;
    try {
      started = true;
      int64_t seq = feeder->feed(channel, rbuf->data, static_cast<int>(rbuf->data_size));
      for (auto& a : feeder->analyzers()) {
        if (!a->take_new_points().empty()) {
          frd_t m = to_frd_msg(a->frd(), feeder->run_id(), frd_seq++, a->done());
          lcm->publish(kFrdChannel, &m);
        }
      }
      if (seq >= 0) ack(seq);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  void ack(int64_t seq) {
    ack_t a;
    a.run_id = feeder->run_id();
    a.consumer = name;
    a.seq = seq;
    ctl->publish(kAckChannel, &a);
  }
};

void write_frds(const std::vector<Frd>& frds, const std::string& out) {
  std::filesystem::create_directories(out + "/frd");
  for (const Frd& f : frds) save_frd(out + "/frd/" + pair_file_stem(f.pair) + ".json", f);
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
  app.add_option("--log", log, "tape mode: read this LCM log file directly (no LCM traffic)");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!log.empty()) {
      auto frds = analyze_tape_file(log, pairs, opt);
      if (!out.empty()) write_frds(frds, out);
      for (const Frd& f : frds) std::cout << frd_to_json(f).dump() << "\n";
      return 0;
    }
    TapeFeeder feeder(pairs, opt, run_id);
    lcm::LCM lcm(resolve_lcm_url(url));
    if (!lcm.good()) throw InputError("cannot open LCM at " + resolve_lcm_url(url));
    lcm::LCM ctl(ctl_url.empty() ? control_url_for(resolve_lcm_url(url))
                                 : resolve_lcm_url(ctl_url));
    if (!ctl.good()) throw InputError("cannot open the control LCM URL");
    Live live{&feeder, &lcm, &ctl, name.empty() ? pairs.front() : name, false, 0, ""};
    for (const char* ch : {kTapeChannel, kStatusChannel}) {
      lcm.subscribe(ch, &Live::on_msg, &live)->setQueueCapacity(100000);
    }
    auto last_ready = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    while (!feeder.all_done()) {
      if (!live.started &&
          std::chrono::steady_clock::now() - last_ready > std::chrono::milliseconds(100)) {
        live.ack(-1);  // ready
        last_ready = std::chrono::steady_clock::now();
      }
      lcm.handleTimeout(100);
      if (!live.error.empty()) throw InputError(live.error);
    }
    std::vector<Frd> frds;
    for (auto& a : feeder.analyzers()) {
      frds.push_back(a->frd());
      frd_t m = to_frd_msg(frds.back(), feeder.run_id(), live.frd_seq++, true);
      lcm.publish(kFrdChannel, &m);
    }
    if (!out.empty()) write_frds(frds, out);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-analyze: " << e.what() << "\n";
    return 1;
  }
}
