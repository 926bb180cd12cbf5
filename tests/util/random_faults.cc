#include "random_faults.h"

#include <algorithm>
#include <cmath>

#include "fralab/core/text.h"

namespace fralab::testing {

InjectedFault add_random_fault(Model& m, const TimeSeries& clean, std::mt19937_64& g) {
  std::uniform_int_distribution<size_t> pick_out(0, m.outputs.size() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ModelOutput& o = m.outputs[pick_out(g)];
  const int c = clean.channel_index(o.name);
  double lo = INFINITY, hi = -INFINITY, mean = 0, var = 0;
  for (int64_t k = 0; k < clean.n_samples; ++k) {
    const double v = clean.at(size_t(c), k);
    lo = std::min(lo, v), hi = std::max(hi, v);
    mean += v / double(clean.n_samples);
  }
  for (int64_t k = 0; k < clean.n_samples; ++k)
    var += std::pow(clean.at(size_t(c), k) - mean, 2) / double(clean.n_samples);
  const double sd = std::sqrt(var), T = double(clean.n_samples) / clean.sample_rate_hz;
  const double noise = std::max(o.noise_rms, 1e-3 * sd);
  InjectedFault in;
  in.channel = o.name;
  ChannelFault f;
  switch (std::uniform_int_distribution<int>(0, 6)(g)) {
    case 0: {  // clipped at 60-90 % of the swing on one side or both
      f.kind = ChannelFaultKind::kClip;
      const double share = 0.6 + 0.3 * u(g);
      const int side = std::uniform_int_distribution<int>(0, 2)(g);
      if (side != 1) f.max = mean + share * (hi - mean);
      if (side != 0) f.min = mean - share * (mean - lo);
      in.kind = DataFaultKind::kClipping;
      in.text = "clip at " + significant(share * 100, 3) + " % of the swing";
      break;
    }
    case 1: {  // hum 0.5-5 noise rms at 50 or 60 Hz, with its 3rd harmonic half the time
      f.kind = ChannelFaultKind::kHum;
      f.frequency_hz = u(g) < 0.5 ? 50.0 : 60.0;
      f.amplitude = noise * (0.5 + 4.5 * u(g));
      if (u(g) < 0.5) f.harmonics = {1, 3};
      f.phase_deg = 360 * u(g);
      in.kind = DataFaultKind::kHum;
      in.size = f.amplitude;
      in.text = "hum " + significant(f.frequency_hz, 3) + " Hz x" +
                std::to_string(f.harmonics.size()) + ", " + significant(f.amplitude / noise, 3) +
                " noise rms";
      break;
    }
    case 2: {  // drift of 0.5-3 response sd over the run
      f.kind = ChannelFaultKind::kDrift;
      f.rate = (u(g) < 0.5 ? -1 : 1) * sd * (0.5 + 2.5 * u(g)) / T;
      in.kind = DataFaultKind::kDrift;
      in.size = f.rate;
      in.text = "drift " + significant(f.rate * T / sd, 3) + " sd over the run";
      break;
    }
    case 3:
    case 4: {  // dropouts, 0.2-3 a second, 1-20 samples, held or lost
      f.kind = ChannelFaultKind::kDropouts;
      f.rate_hz = 0.2 + 2.8 * u(g);
      f.length = 1 + int(20 * u(g));
      f.held = u(g) < 0.5;
      in.kind = f.held ? DataFaultKind::kHeld : DataFaultKind::kLost;
      in.text = std::string(f.held ? "held" : "lost") + " dropouts " + significant(f.rate_hz, 3) +
                "/s x " + std::to_string(f.length);
      break;
    }
    case 5: {  // dead from 30-80 % of the run
      f.kind = ChannelFaultKind::kDead;
      f.from_s = T * (0.3 + 0.5 * u(g));
      in.kind = DataFaultKind::kNoResponse;
      in.text = "dead from " + significant(f.from_s, 3) + " s";
      break;
    }
    default: {  // clock 1e-4 .. 1e-3 fast
      f.kind = ChannelFaultKind::kClock;
      f.rate_error = std::pow(10.0, -4 + u(g));
      in.kind = DataFaultKind::kClock;
      in.size = f.rate_error / (1 + f.rate_error);
      in.text = "clock " + significant(f.rate_error * 100, 3) + " % fast";
      break;
    }
  }
  for (const ChannelFault& x : o.faults)
    if (x.kind == f.kind) return add_random_fault(m, clean, g);  // one of a kind per channel
  o.faults.push_back(f);
  return in;
}

void FaultScore::add(const FaultScore& o) {
  put += o.put, named += o.named, to_size += o.to_size, sized += o.sized;
  false_named += o.false_named;
  lines.insert(lines.end(), o.lines.begin(), o.lines.end());
}

FaultScore score_faults(const std::vector<InjectedFault>& put, const std::vector<DataFault>& got) {
  FaultScore s;
  std::vector<bool> matched(got.size(), false);
  for (const InjectedFault& in : put) {
    ++s.put;
    const DataFault* hit = nullptr;
    for (size_t k = 0; k < got.size(); ++k)
      if (got[k].channel == in.channel && got[k].kind == in.kind) {
        matched[k] = true;
        hit = hit ? hit : &got[k];
      }
    s.named += hit != nullptr;
    if (!hit) s.lines.push_back("missed: " + in.channel + " " + to_string(in.kind));
    if (hit && in.size != 0) {
      ++s.to_size;
      const bool ok = std::abs(hit->size - in.size) <= 0.1 * std::abs(in.size);
      s.sized += ok;
      if (!ok)
        s.lines.push_back("sized " + in.channel + " " + to_string(in.kind) + ": " +
                          significant(hit->size, 4) + ", put in " + significant(in.size, 4));
    }
  }
  for (size_t k = 0; k < got.size(); ++k)
    if (!matched[k]) {
      ++s.false_named;
      s.lines.push_back("named, not put in: " + got[k].text);
    }
  return s;
}

}  // namespace fralab::testing
