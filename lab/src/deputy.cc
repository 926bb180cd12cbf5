#include "fralab/lab/deputy.h"

#include <csignal>
#include <filesystem>

#include "fralab/deputy_order_t.hpp"
#include "fralab/deputy_report_t.hpp"

namespace fralab {

DeputyClient::DeputyClient(lcm::LCM& lcm, std::string run_id, double silence_s)
    : lcm_(lcm), run_id_(std::move(run_id)), silence_s_(silence_s) {
  sub_ = lcm_.subscribe(kDeputyReportChannel, &DeputyClient::on_report, this);
  sub_->setQueueCapacity(10000);
}

DeputyClient::~DeputyClient() { lcm_.unsubscribe(sub_); }

void DeputyClient::send(Order& o) {
  deputy_order_t m;
  m.deputy = o.spec.host;
  m.run_id = run_id_;
  m.name = o.spec.name;
  m.action = o.action;
  m.argv = o.spec.argv;
  m.n_args = int32_t(m.argv.size());
  m.log_file = o.spec.log_file;
  lcm_.publish(kDeputyOrderChannel, &m);
  o.sent = Clock::now();
}

void DeputyClient::start(const ProcessSpec& spec) {
  in_use_.insert(spec.host);
  Order& o = orders_[spec.name] = Order{spec, "start"};
  send(o);
}

void DeputyClient::stop(const std::string& name) {
  auto it = orders_.find(name);
  if (it == orders_.end() || exits_.count(name)) return;
  it->second.action = "stop";
  it->second.answered = false;
  send(it->second);
}

void DeputyClient::on_report(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const deputy_report_t r = decode_checked<deputy_report_t>(rbuf, channel);
  heard_[r.deputy] = Clock::now();
  if (r.run_id != run_id_ || r.name.empty()) return;
  auto it = orders_.find(r.name);
  if (it == orders_.end() || it->second.spec.host != r.deputy) return;
  if (r.state == "exited") {
    exits_[r.name] = Exit{r.exit_status, r.reason};
    it->second.answered = true;
  } else if (r.state == "running" && it->second.action == "start") {
    it->second.answered = true;
  }
}

void DeputyClient::poll(int ms) {
  lcm_.handleTimeout(ms);
  while (lcm_.handleTimeout(0) > 0) {
  }
  for (auto& [n, o] : orders_)
    if (!o.answered && Clock::now() - o.sent > std::chrono::milliseconds(300)) send(o);
}

std::optional<RemoteProcesses::Exit> DeputyClient::exited(const std::string& name) const {
  auto it = exits_.find(name);
  if (it == exits_.end()) return std::nullopt;
  return it->second;
}

std::string DeputyClient::silent_deputy() const {
  for (const auto& d : in_use_) {
    auto h = heard_.find(d);
    const double quiet =
        h == heard_.end() ? 1e9 : std::chrono::duration<double>(Clock::now() - h->second).count();
    if (quiet > silence_s_)
      return "deputy \"" + d + "\" is silent" +
             (h == heard_.end() ? std::string(" (never heard)")
                                : " for " + std::to_string(int(quiet)) + " s") +
             ": its host is down or cut off (its processes are lost)";
  }
  return "";
}

void DeputyClient::wait_for_deputy(const std::string& deputy, double timeout_s) {
  const auto t0 = Clock::now();
  while (!heard_.count(deputy)) {
    poll(50);
    if (std::chrono::duration<double>(Clock::now() - t0).count() > timeout_s)
      throw InputError("deputy \"" + deputy + "\" not heard within " +
                       std::to_string(int(timeout_s)) + " s: is `fralab-deputy --name " + deputy +
                       "` running on that host, on the same deputy URL, with FRALAB_NETWORK=1?");
  }
}

DeputyNode::DeputyNode(lcm::LCM& lcm, std::string name) : lcm_(lcm), name_(std::move(name)) {
  lcm_.subscribe(kDeputyOrderChannel, &DeputyNode::on_order, this)->setQueueCapacity(10000);
}

DeputyNode::~DeputyNode() { sup_.stop_all(); }

void DeputyNode::on_order(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  try {
    const deputy_order_t o = decode_checked<deputy_order_t>(rbuf, channel);
    if (o.deputy != name_) return;
    const std::string key = o.run_id + "/" + o.name;
    if (o.action == "start") {
      if (runs_.count(key)) return;  // repeated order
      runs_[key] = o.run_id;
      ProcessSpec spec{key, o.argv, o.log_file, ""};
      // The launcher's paths to fralab modules become this host's (beside this deputy).
      for (auto& a : spec.argv) {
        const std::string file = std::filesystem::path(a).filename().string();
        if (file.rfind("fralab-", 0) == 0 && a.find('/') != std::string::npos)
          a = module_path(file);
      }
      try {
        sup_.start(spec);
      } catch (const InputError& e) {
        failed_[key] = o.name + " could not be started on " + name_ + ": " + e.what();
      }
    } else if (o.action == "stop" && runs_.count(key)) {
      sup_.stop(key, SIGTERM, 5.0);
    }
    report();
  } catch (const std::exception& e) {
    error_ = e.what();
  }
}

void DeputyNode::report() {
  deputy_report_t alive;
  alive.deputy = name_;
  alive.state = "alive";
  alive.exit_status = 0;
  lcm_.publish(kDeputyReportChannel, &alive);
  sup_.poll();
  for (const auto& [key, run] : runs_) {
    deputy_report_t r;
    r.deputy = name_;
    r.run_id = run;
    r.name = key.substr(run.size() + 1);
    auto e = sup_.exit_of(key);
    if (failed_.count(key)) e = RemoteProcesses::Exit{127, failed_[key]};
    r.state = e ? "exited" : "running";
    r.exit_status = e ? e->status : 0;
    r.reason = e ? e->reason : "";
    // The local reason names the process by its key; the launcher knows it by its name.
    if (r.reason.rfind(key, 0) == 0) r.reason = r.name + r.reason.substr(key.size());
    lcm_.publish(kDeputyReportChannel, &r);
  }
  last_report_ = std::chrono::steady_clock::now();
}

void DeputyNode::tick(int ms) {
  lcm_.handleTimeout(ms);
  if (std::chrono::steady_clock::now() - last_report_ > std::chrono::milliseconds(200)) report();
}

}  // namespace fralab
