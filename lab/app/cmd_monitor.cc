// `fralab monitor`: follow a running lab (its FRALAB_FRD on --lcm-url) or a tape being written
// (--log, read as it grows) and print the chosen pair's points as they arrive, beside the
// simulation when --simulation is given (lab/monitor.h). Ends when the pair is complete (the
// analyser's final curve, or the tape's final block analysed), or after --idle seconds without
// anything new.
#include <chrono>
#include <iostream>
#include <map>
#include <memory>
#include <thread>

#include "commands.h"
#include "fralab/diagnose/diagnose.h"
#include "fralab/envelope/envelope.h"
#include "fralab/lab/monitor.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/lab_lcm.h"
#include "fralab/lcm/tape_file.h"
#include "fralab/lcm/url.h"
#include "fralab/plant/embedded_models.h"
#include "tape_analysis.h"

namespace fralab {

namespace {

struct MonitorCommand {
  std::string pair, url, log, simulation, run_id, plot;
  double idle_s = 10;
};

void run(const MonitorCommand& c) {
  std::optional<Model> sim;
  if (!c.simulation.empty()) sim = load_model_or_scheduled(c.simulation);
  std::cout << c.pair << (sim ? " against " + sim->name : std::string()) << "\n"
            << monitor_header(bool(sim)) << "\n";
  // By w and validity: a point is printed once (a step repeated after a refused point, e.g. a
  // free-running plant's dry buffer, shows again).
  std::map<std::pair<double, bool>, FrdPoint> shown;
  auto sim_at = [&](const FrdPoint& p) -> std::optional<std::complex<double>> {
    if (!sim) return std::nullopt;
    return model_pair_response(*sim, c.pair, p.w, p.amplitude);
  };
  const std::string title = c.pair + (sim ? " against " + sim->name : std::string());
  auto plot = [&](bool live) {
    if (c.plot.empty()) return;
    std::vector<FrdPoint> pts;
    for (const auto& [w, p] : shown) pts.push_back(p);
    write_monitor_page(c.plot, title, pts, sim_at, live);
  };
  plot(true);
  auto show = [&](const Frd& f) {
    bool added = false;
    for (const FrdPoint& p : f.points) {
      if (shown.count({p.w, p.valid})) continue;
      shown[{p.w, p.valid}] = p;
      added = true;
      std::cout << monitor_row(p, sim_at(p)) << "\n" << std::flush;
    }
    if (added) plot(true);
  };
  using Clock = std::chrono::steady_clock;
  auto last_new = Clock::now();
  auto idle = [&] {
    return std::chrono::duration<double>(Clock::now() - last_new).count() > c.idle_s;
  };
  if (!c.log.empty()) {  // a tape, perhaps still being written
    TapeFeeder feeder({c.pair}, {}, c.run_id);
    int64_t offset = 0;
    while (!feeder.all_done() && !idle()) {
      const int64_t n = follow_tape_file(c.log, &offset, [&](const TapeEvent& ev) {
        feeder.feed(ev.channel, ev.data, ev.datalen);
      });
      if (n > 0) last_new = Clock::now();
      show(feeder.analyzers()[0]->frd());
      if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (!feeder.all_done()) feeder.flush();
    show(feeder.analyzers()[0]->frd());
    plot(false);
    return;
  }
  lcm::LCM lcm(resolve_lcm_url(c.url));
  require_lcm(lcm, "LCM", resolve_lcm_url(c.url));
  // A growing curve's messages carry its new points, the finished curve's all of them
  // (docs/lcm-protocol.md): each message's points are shown as they come.
  struct Listener {
    const MonitorCommand* c = nullptr;
    std::vector<Frd> arrived;
    bool complete = false;
    void on_frd(const lcm::ReceiveBuffer* rb, const std::string& ch) {
      const frd_t m = decode_checked<frd_t>(rb, ch);
      if (m.pair != c->pair || (!c->run_id.empty() && m.run_id != c->run_id)) return;
      arrived.push_back(from_frd_msg(m));
      complete |= m.complete;
    }
  } listener;
  listener.c = &c;
  lcm.subscribe(kFrdChannel, &Listener::on_frd, &listener)->setQueueCapacity(10000);
  while (!listener.complete && !idle()) {
    lcm.handleTimeout(100);
    if (listener.arrived.empty()) continue;
    last_new = Clock::now();
    for (const Frd& f : listener.arrived) show(f);
    listener.arrived.clear();
  }
  for (const Frd& f : listener.arrived) show(f);
  plot(false);
}

}  // namespace

void add_monitor_command(CLI::App& app) {
  auto mc = std::make_shared<MonitorCommand>();
  auto* c =
      app.add_subcommand("monitor", "follow a running lab or a tape: one pair, point by point");
  c->add_option("--pair", mc->pair, "E1:E2 (response E2/E1)")->required();
  auto* url = c->add_option("--lcm-url", mc->url, "a running lab's URL (its run.json lcm_url)");
  c->add_option("--log", mc->log, "a tape, complete or still being written")->excludes(url);
  c->add_option("--simulation", mc->simulation, "model file or embedded name to compare with");
  c->add_option("--run-id", mc->run_id, "only this run");
  c->add_option("--plot", mc->plot,
                "also a live Bode plot: this HTML page, redrawn at each point, reloading itself "
                "until the pair is complete");
  c->add_option("--idle", mc->idle_s, "stop after this many seconds without a new point")
      ->capture_default_str();
  c->callback([mc] { run(*mc); });
}

}  // namespace fralab
