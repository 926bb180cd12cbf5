// fralab-acquire: the oscillator. Holds every actuator at its operating point, adds the test signal
// on the selected inputs (stepped sine, one input after the other), publishes command blocks
// (FRALAB_CMD) with the reference channels and excitation status (FRALAB_STATUS), and drives the
// plant in lockstep. Flow control: it waits until the plant and every named consumer have
// acknowledged blocks up to seq - window before sending more, so nothing is ever dropped;
// --speed 1 additionally paces blocks at real time (a real test cell), --speed 0 goes as fast as
// the consumers keep up. The results depend only on the samples, never on the speed.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <thread>

#include "fralab/acquire/campaign.h"
#include "fralab/acquire/model_info.h"
#include "fralab/lcm_io.h"
#include "fralab/plant/embedded_models.h"

using namespace fralab;
using Clock = std::chrono::steady_clock;

namespace {

struct Acq {
  std::string run_id;
  std::map<std::string, int64_t> acked;  // consumer -> last seq (-1 = ready)
  std::string error;

  void on_ack(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    try {
      ack_t a = decode_checked<ack_t>(rbuf, ch);
      if (!a.run_id.empty() && a.run_id != run_id) return;
      auto it = acked.find(a.consumer);
      if (it == acked.end())
        acked[a.consumer] = a.seq;
      else
        it->second = std::max(it->second, a.seq);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  int64_t min_ack(const std::vector<std::string>& who, std::string* laggard) const {
    int64_t m = INT64_MAX;
    for (const auto& c : who) {
      auto it = acked.find(c);
      int64_t v = it == acked.end() ? -2 : it->second;
      if (v < m) {
        m = v;
        if (laggard) *laggard = c;
      }
    }
    return m;
  }
};

std::vector<std::string> split_csv(const std::string& s) {
  std::vector<std::string> out;
  size_t a = 0;
  while (a <= s.size()) {
    size_t b = s.find(',', a);
    if (b == std::string::npos) b = s.size();
    if (b > a) out.push_back(s.substr(a, b - a));
    a = b + 1;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-acquire: excitation campaign over LCM"};
  std::string engine = "j85_95", inputs_csv, band = "0.04:100", url, ctl_url, run_id = "run",
              consumers_csv = "plant", summary;
  SteppedSineOptions so;
  double amplitude_pct = -1, amplitude_scale = 1, speed = 0, ready_timeout = 30, stall_timeout = 60;
  int block = 100, window = 2;
  std::string excitation = "stepped", ms_phases = "schroeder";
  bool odd_lines = false;
  app.add_option("--engine", engine, "engine model (file or embedded name)")->capture_default_str();
  app.add_option("--input", inputs_csv, "input(s) to excite, comma separated (default: all)");
  app.add_option("--band", band, "LO_HZ:HI_HZ")->capture_default_str();
  app.add_option("--excitation", excitation,
                 "stepped (stepped sine), sweep (continuous log sweep) or multisine (all inputs at "
                 "once, orthogonal lines; --min-cycles = periods)")
      ->capture_default_str();
  app.add_option("--multisine-phases", ms_phases, "schroeder or random")->capture_default_str();
  app.add_flag("--odd-lines", odd_lines, "multisine: odd harmonics only");
  app.add_option("--points-per-decade", so.points_per_decade)->capture_default_str();
  app.add_option("--amplitude-pct", amplitude_pct,
                 "amplitude, % of full scale (default: the input's test_amplitude_pct, else 2)");
  app.add_option("--amplitude-scale", amplitude_scale, "multiplies every input's amplitude")
      ->capture_default_str();
  app.add_option("--min-cycles", so.min_cycles)->capture_default_str();
  app.add_option("--min-integrate-s", so.min_integrate_s)->capture_default_str();
  app.add_option("--sample-rate", so.sample_rate_hz)->capture_default_str();
  app.add_option("--speed", speed, "1 = real time, 100 = 100x, 0 = as fast as consumers keep up")
      ->capture_default_str();
  app.add_option("--block", block, "samples per command block")->capture_default_str();
  app.add_option("--window", window, "blocks in flight ahead of the slowest consumer")
      ->capture_default_str();
  app.add_option("--consumers", consumers_csv,
                 "who must acknowledge (plant is implicit via its tape)")
      ->capture_default_str();
  app.add_option("--run-id", run_id)->capture_default_str();
  app.add_option("--lcm-url", url);
  app.add_option("--control-url", ctl_url,
                 "LCM URL for acknowledgements (default: --lcm-url with port + 1)");
  app.add_option("--ready-timeout", ready_timeout, "seconds to wait for consumers to be ready")
      ->capture_default_str();
  app.add_option("--summary", summary, "write a JSON summary here");
  CLI11_PARSE(app, argc, argv);
  try {
    Model model = load_model_or_embedded(engine);
    auto [lo, hi] = parse_band(band);
    so.f_lo_hz = lo;
    so.f_hi_hz = hi;
    so.slowest_time_constant_s = slowest_time_constant_s(model);
    if (block < 1 || block * 8.0 * (model.inputs.size() * 2 + model.outputs.size() + 2) > 60000) {
      throw InputError("--block " + std::to_string(block) +
                       " would make tape blocks over 60 kB (LCM fragments); use a smaller block");
    }
    if (window < 1) throw InputError("--window must be >= 1");
    if (speed < 0) throw InputError("--speed must be >= 0");
    std::vector<int> excite = select_inputs(model, inputs_csv);
    auto cin = campaign_inputs(model, amplitude_pct, amplitude_scale);
    std::unique_ptr<Campaign> campaign;
    if (excitation == "stepped") {
      campaign = std::make_unique<SteppedSineCampaign>(cin, excite, plan_stepped_sine(so),
                                                       so.sample_rate_hz, run_id);
    } else if (excitation == "sweep") {
      campaign = std::make_unique<SweepCampaign>(cin, excite, so, run_id);
    } else if (excitation == "multisine") {
      MultisineOptions mo;
      mo.f_lo_hz = so.f_lo_hz;
      mo.f_hi_hz = so.f_hi_hz;
      mo.points_per_decade = so.points_per_decade;
      mo.periods = std::max(2, so.min_cycles);
      mo.slowest_time_constant_s = so.slowest_time_constant_s;
      mo.sample_rate_hz = so.sample_rate_hz;
      mo.odd_lines = odd_lines;
      mo.phases = ms_phases;
      campaign = std::make_unique<MultisineCampaign>(cin, excite, mo, run_id);
    } else {
      throw InputError("--excitation \"" + excitation + "\": stepped, sweep or multisine");
    }
    const Campaign& camp = *campaign;

    lcm::LCM lcm(resolve_lcm_url(url));
    if (!lcm.good()) throw InputError("cannot open LCM at " + resolve_lcm_url(url));
    Acq acq;
    acq.run_id = run_id;
    lcm::LCM ctl(ctl_url.empty() ? control_url_for(resolve_lcm_url(url))
                                 : resolve_lcm_url(ctl_url));
    if (!ctl.good()) throw InputError("cannot open the control LCM URL");
    ctl.subscribe(kAckChannel, &Acq::on_ack, &acq)->setQueueCapacity(100000);
    std::vector<std::string> consumers = split_csv(consumers_csv);
    if (std::find(consumers.begin(), consumers.end(), "plant") == consumers.end())
      consumers.push_back("plant");

    // Waits until every consumer has acknowledged `target` (-1: ready); past `timeout` seconds the
    // error names the slowest consumer (`lag`) through `why`.
    std::string lag;
    auto wait_acks = [&](int64_t target, double timeout, int poll_ms,
                         const std::function<std::string()>& why) {
      const auto t = Clock::now();
      while (acq.min_ack(consumers, &lag) < target) {
        handle_either(lcm, ctl, poll_ms);
        if (!acq.error.empty()) throw InputError(acq.error);
        if (std::chrono::duration<double>(Clock::now() - t).count() > timeout)
          throw InputError(why());
      }
    };
    wait_acks(-1, ready_timeout, 50, [&] {
      return "consumer \"" + lag + "\" never said ready within " + std::to_string(ready_timeout) +
             " s (is it running on the same LCM URL?)";
    });
    auto publish_status = [&](const StatusEvent& e) {
      excitation_status_t m = to_status_msg(e);
      lcm.publish(kStatusChannel, &m);
    };
    StatusEvent start = camp.events().front();
    start.state = "start";
    start.seq = -1;
    start.sample = 0;
    start.n_samples = camp.total_samples();
    publish_status(start);

    const auto t0 = Clock::now();
    const int64_t total = camp.total_samples();
    const int64_t nblocks = (total + block - 1) / block;
    size_t ev = 0;
    std::vector<std::vector<double>> cmd;
    std::vector<double> ref_phase, ref_freq;
    for (int64_t b = 0; b < nblocks; ++b) {
      wait_acks(b - window, stall_timeout, 20, [&] {
        return "consumer \"" + lag + "\" stopped acknowledging at block " +
               std::to_string(acq.min_ack(consumers, nullptr)) + " (sent up to " +
               std::to_string(b - 1) + ")";
      });
      const int64_t s0 = b * block;
      const int n = int(std::min<int64_t>(block, total - s0));
      if (speed > 0) {
        auto due = t0 + std::chrono::duration<double>(double(s0) / so.sample_rate_hz / speed);
        while (Clock::now() < due)
          handle_either(
              lcm, ctl,
              1 + int(std::chrono::duration<double, std::milli>(due - Clock::now()).count()));
      }
      const bool last = b == nblocks - 1;
      while (ev < camp.events().size() && (camp.events()[ev].sample < s0 + n || last))
        publish_status(camp.events()[ev++]);
      camp.fill(s0, n, cmd, ref_phase, ref_freq);
      Block blk;
      blk.run_id = run_id;
      blk.seq = b;
      blk.start_sample = s0;
      blk.sample_rate_hz = so.sample_rate_hz;
      blk.n_samples = n;
      blk.final_block = last;
      for (const auto& in : camp.inputs()) blk.channels.push_back("u_" + in.name);
      blk.channels.push_back("ref_phase");
      blk.channels.push_back("ref_freq_hz");
      blk.samples.reserve(blk.channels.size() * n);
      for (const auto& c : cmd) blk.samples.insert(blk.samples.end(), c.begin(), c.end());
      blk.samples.insert(blk.samples.end(), ref_phase.begin(), ref_phase.end());
      blk.samples.insert(blk.samples.end(), ref_freq.begin(), ref_freq.end());
      command_block_t m = to_command_msg(blk);
      lcm.publish(kCmdChannel, &m);
    }
    // Wait for everyone to take the last block.
    wait_acks(nblocks - 1, stall_timeout, 20, [&] {
      return "consumer \"" + lag + "\" did not acknowledge the final block " +
             std::to_string(nblocks - 1);
    });
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const double engine_s = double(total) / so.sample_rate_hz;
    Json sj{{"run_id", run_id},        {"engine_time_s", engine_s},
            {"wall_time_s", wall},     {"speedup", engine_s / std::max(wall, 1e-9)},
            {"blocks", nblocks},       {"samples", total},
            {"excitation", excitation}};
    std::cerr << "fralab-acquire: " << sj.dump() << "\n";
    if (!summary.empty()) json_save_file(summary, sj);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-acquire: " << e.what() << "\n";
    return 1;
  }
}
