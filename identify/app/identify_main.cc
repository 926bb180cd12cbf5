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

#include "fralab/core/measure_dir.h"
#include "fralab/identify/fit_io.h"
#include "fralab/lcm/lab_lcm.h"
#include "fralab/lcm/url.h"
#include "identifier_node.h"

using namespace fralab;

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
    IdentifierNode node(lcm, run_id);
    const auto t0 = std::chrono::steady_clock::now();
    auto last_ready = t0 - std::chrono::seconds(1);
    while (int(node.curves().size()) < expect) {
      // Says it is there, so the analysers hand their curves over until acknowledged.
      if (std::chrono::steady_clock::now() - last_ready > std::chrono::milliseconds(500)) {
        node.announce_ready();
        last_ready = std::chrono::steady_clock::now();
      }
      lcm.handleTimeout(100);
      if (!node.error().empty()) throw InputError(node.error());
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout) {
        throw InputError("only " + std::to_string(node.curves().size()) + " of " +
                         std::to_string(expect) + " curves arrived");
      }
    }
    node.fit_and_publish(o, out, title);
    // Copies republished while fitting (an acknowledgement was lost) are acknowledged again.
    const auto t_end = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (std::chrono::steady_clock::now() < t_end) lcm.handleTimeout(100);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-identify: " << e.what() << "\n";
    return 1;
  }
}
