// Deputies: one `fralab-deputy` per host starts and stops the lab's module processes for a
// launcher on another host, over LCM, as procman's deputies do. Multi-host is an explicit opt-in
// (FRALAB_NETWORK=1, URLs with ttl >= 1, lcm/url.h).
//
// Protocol (lcmtypes deputy_order_t / deputy_report_t, on the deputies' URL):
//   launcher -> FRALAB_DEPUTY_ORDER: "start" (argv, log file) or "stop" one named process of a
//     run on one deputy; repeated every 300 ms until a report answers it (a start by a report of
//     that process, a stop by its "exited"); a repeated order is harmless.
//   deputy -> FRALAB_DEPUTY_REPORT every 200 ms: a heartbeat (name "", state "alive") and, per
//     process it runs for a run, "running" or "exited" with its status and reason.
// A deputy silent for `silence_s` fails the run naming it (a host down or cut off).
#pragma once

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "fralab/lab/supervisor.h"
#include "fralab/lcm/codec.h"

namespace fralab {

inline constexpr const char* kDeputyOrderChannel = "FRALAB_DEPUTY_ORDER";
inline constexpr const char* kDeputyReportChannel = "FRALAB_DEPUTY_REPORT";
/// The deputies' URL unless given: a fixed group and port, ttl=1 (needs FRALAB_NETWORK=1).
inline constexpr const char* kDefaultDeputyUrl = "udpm://239.255.76.70:7670?ttl=1";

/// The launcher's side: RemoteProcesses through the deputies.
class DeputyClient : public RemoteProcesses {
 public:
  DeputyClient(lcm::LCM& lcm, std::string run_id, double silence_s = 5.0);
  ~DeputyClient() override;
  void start(const ProcessSpec& spec) override;
  void stop(const std::string& name) override;
  void poll(int ms) override;
  std::optional<Exit> exited(const std::string& name) const override;
  std::string silent_deputy() const override;
  /// Waits up to timeout_s for a heartbeat of `deputy`; InputError naming it otherwise.
  void wait_for_deputy(const std::string& deputy, double timeout_s);

 private:
  using Clock = std::chrono::steady_clock;
  struct Order {
    ProcessSpec spec;
    std::string action;
    Clock::time_point sent{};
    bool answered = false;
  };
  void on_report(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void send(Order& o);
  lcm::LCM& lcm_;
  lcm::Subscription* sub_ = nullptr;
  std::string run_id_;
  double silence_s_;
  std::map<std::string, Order> orders_;  // by process name
  std::map<std::string, Exit> exits_;
  std::map<std::string, Clock::time_point> heard_;  // deputy -> last heartbeat
  std::set<std::string> in_use_;
};

/// The deputy's side (fralab-deputy): starts what it is ordered to on this host, with a local
/// Supervisor, and reports.
class DeputyNode {
 public:
  DeputyNode(lcm::LCM& lcm, std::string name);
  ~DeputyNode();
  /// Handles orders for up to `ms`, notes exits, and reports every 200 ms.
  void tick(int ms);
  /// Stops every process it started.
  void stop_all() { sup_.stop_all(); }
  const std::string& error() const { return error_; }

 private:
  void on_order(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void report();
  lcm::LCM& lcm_;
  std::string name_;
  Supervisor sup_;
  std::map<std::string, std::string> runs_;    // process key (run/name) -> run id
  std::map<std::string, std::string> failed_;  // key -> why it could not be started
  std::chrono::steady_clock::time_point last_report_{};
  std::string error_;
};

}  // namespace fralab
