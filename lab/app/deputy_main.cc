// fralab-deputy: starts and stops the lab's module processes on this host for a launcher on
// another host (lab/deputy.h), until SIGINT or SIGTERM (then it stops them too). Multi-host is an
// explicit opt-in: the deputies' URL has ttl >= 1 and needs FRALAB_NETWORK=1.
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>

#include "fralab/lab/deputy.h"
#include "fralab/lcm/lab_lcm.h"
#include "fralab/lcm/url.h"

using namespace fralab;

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-deputy: the lab's processes on this host, for a launcher elsewhere"};
  std::string name, url = kDefaultDeputyUrl;
  app.add_option("--name", name, "this deputy's name (the launcher's --on PROCESS=NAME)")
      ->required();
  app.add_option("--lcm-url", url, "the deputies' LCM URL")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  try {
    lcm::LCM lcm(resolve_lcm_url(url));
    require_lcm(lcm, "LCM", url);
    DeputyNode deputy(lcm, name);
    while (!g_stop) {
      deputy.tick(100);
      if (!deputy.error().empty()) {
        std::cerr << "fralab-deputy: " << deputy.error() << "\n";
        return 1;
      }
    }
    deputy.stop_all();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-deputy: " << e.what() << "\n";
    return 1;
  }
}
