// fralab-identify: the live identifier. Collects the analysers' finished curves of a run
// (FRALAB_FRD, complete = true, each acknowledged on FRALAB_FRD_ACK), fits every pair, publishes
// each fit (FRALAB_TF), and writes DIR/tf/<E1>_<E2>.json and the transfer matrix
// DIR/transfer_matrix.{json,md}. With --from-frd DIR it fits the curves DIR/frd/<E1>_<E2>.json of
// the pairs given (--pair, repeated) instead, without LCM: the launcher's fit of a resumed run or
// an auto campaign, in a process of its own so that a crash in fitting leaves the curves whole.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <iostream>
#include <map>

#include "fralab/core/measure_dir.h"
#include "fralab/identify/fit_io.h"
#include "fralab/lcm_io.h"

using namespace fralab;

namespace {

// Complete curves of the run, each acknowledged to its analyser (FRALAB_FRD_ACK on the data URL,
// consumer "identify", stream "frd:<pair>"; again for every copy, so a lost one is mended).
struct Collector {
  std::string run_id;
  lcm::LCM* control = nullptr;
  std::map<std::string, Frd> complete;
  std::string error;
  void on_frd(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    try {
      frd_t m = decode_checked<frd_t>(rbuf, ch);
      if (!run_id.empty() && m.run_id != run_id) return;
      if (!m.complete) return;
      if (!complete.count(m.pair)) complete[m.pair] = from_frd_msg(m);
      publish_ack(*control, m.run_id, "identify", "frd:" + m.pair, 0, kFrdAckChannel);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-identify: transfer functions and the transfer matrix of a run"};
  std::string url, out, run_id, delay = "auto", title = "fralab transfer matrix";
  int expect = 0;
  double timeout = 3600;
  app.add_option("--lcm-url", url);
  app.add_option("--run-id", run_id);
  std::string from_frd;
  std::vector<std::string> pairs;
  app.add_option("--expect", expect, "number of pairs to wait for (live)");
  app.add_option("--from-frd", from_frd, "fit DIR/frd/<E1>_<E2>.json of the --pair given, no LCM");
  app.add_option("--pair", pairs, "with --from-frd: a pair E1:E2 (repeatable)");
  app.add_option("--out", out, "writes OUT/tf/*.json and OUT/transfer_matrix.{json,md}")
      ->required();
  app.add_option("--delay", delay, "auto, none or seconds")->capture_default_str();
  app.add_option("--title", title);
  app.add_option("--timeout", timeout, "seconds")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    FitOptions o;
    parse_delay_option(delay, &o);
    if (!from_frd.empty()) {
      if (pairs.empty()) throw InputError("--from-frd " + from_frd + ": no --pair given");
      std::vector<Frd> curves;
      for (const std::string& p : pairs) curves.push_back(load_frd(MeasureDir(from_frd).frd(p)));
      std::sort(curves.begin(), curves.end(),
                [](const Frd& a, const Frd& b) { return a.pair < b.pair; });
      fit_and_write(curves, o, out, title);
      return 0;
    }
    if (expect <= 0) throw InputError("--expect N (the pairs to wait for) or --from-frd DIR");
    lcm::LCM lcm(resolve_lcm_url(url));
    require_lcm(lcm, "LCM", resolve_lcm_url(url));
    Collector c{run_id, &lcm, {}, ""};
    lcm.subscribe(kFrdChannel, &Collector::on_frd, &c)->setQueueCapacity(100000);
    const auto t0 = std::chrono::steady_clock::now();
    auto last_ready = t0 - std::chrono::seconds(1);
    while (int(c.complete.size()) < expect) {
      // Says it is there, so the analysers hand their curves over until acknowledged.
      if (std::chrono::steady_clock::now() - last_ready > std::chrono::milliseconds(500)) {
        publish_ack(lcm, run_id, "identify", "ready", -1, kFrdAckChannel);
        last_ready = std::chrono::steady_clock::now();
      }
      lcm.handleTimeout(100);
      if (!c.error.empty()) throw InputError(c.error);
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout) {
        throw InputError("only " + std::to_string(c.complete.size()) + " of " +
                         std::to_string(expect) + " curves arrived");
      }
    }
    std::vector<Frd> curves;
    for (auto& [p, f] : c.complete) curves.push_back(f);
    auto fits = fit_and_write(curves, o, out, title);
    for (size_t i = 0; i < fits.size(); ++i) {
      tf_t m = to_tf_msg(fits[i].tf, curves[i].pair, run_id, fits[i].e_n, fits[i].status_str());
      lcm.publish(kTfChannel, &m);
    }
    // Copies republished while fitting (an acknowledgement was lost) are acknowledged again.
    const auto t_end = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (std::chrono::steady_clock::now() < t_end) lcm.handleTimeout(100);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-identify: " << e.what() << "\n";
    return 1;
  }
}
