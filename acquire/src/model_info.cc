#include "fralab/acquire/model_info.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fralab/core/text.h"

namespace fralab {

std::pair<double, double> parse_band(const std::string& band) {
  if (const auto lo_hi = number_pair(band)) return *lo_hi;
  throw InputError("--band \"" + band + "\" must be LO_HZ:HI_HZ, e.g. 0.04:100");
}

double slowest_time_constant_s(const Tf& tf) {
  double t = 0.0;
  for (const Root& p : tf.poles)
    t = std::max(t, p.pair ? 1.0 / (p.zeta * p.wn) : 1.0 / std::abs(p.real));
  return t;
}

namespace {

// Calls `scan` on every tf of the model: actuators, sensors, paths.
template <class Scan>
void for_each_tf(const Model& m, Scan scan) {
  for (const auto& in : m.inputs)
    if (in.actuator) scan(*in.actuator);
  for (const auto& out : m.outputs)
    if (out.sensor) scan(*out.sensor);
  for (const auto& p : m.paths) scan(p.tf);
}

}  // namespace

double slowest_time_constant_s(const Model& m) {
  double t = 0.0;
  for_each_tf(m, [&](const Tf& tf) { t = std::max(t, slowest_time_constant_s(tf)); });
  return t;
}

std::vector<ZoomMode> light_modes(const Model& m, double f_lo_hz, double f_hi_hz, double max_zeta) {
  std::vector<ZoomMode> all;
  for_each_tf(m, [&](const Tf& tf) {
    for (const Root& p : tf.poles) {
      const double f = p.wn / (2 * std::numbers::pi);
      if (p.pair && p.zeta > 0 && p.zeta < max_zeta && f >= f_lo_hz && f <= f_hi_hz)
        all.push_back({p.wn, p.zeta});
    }
  });
  std::sort(all.begin(), all.end(),
            [](const ZoomMode& a, const ZoomMode& b) { return a.wn_rad_s < b.wn_rad_s; });
  std::vector<ZoomMode> modes;  // each keeps the lowest wn of the pairs it gathers
  for (const ZoomMode& z : all) {
    if (!modes.empty() && z.wn_rad_s <= 1.01 * modes.back().wn_rad_s)
      modes.back().zeta = std::min(modes.back().zeta, z.zeta);
    else
      modes.push_back(z);
  }
  return modes;
}

std::vector<int> select_inputs(const Model& m, const std::string& csv) {
  std::vector<int> out;
  if (csv.empty()) {
    for (size_t i = 0; i < m.inputs.size(); ++i) out.push_back(int(i));
    return out;
  }
  for (const std::string& name : split_list(csv)) {
    int i = m.input_index(name);
    if (i < 0) {
      std::string known;
      for (const auto& in : m.inputs) known += (known.empty() ? "" : ", ") + in.name;
      throw InputError("--input " + name + ": the model has no such input (inputs: " + known + ")");
    }
    if (std::find(out.begin(), out.end(), i) == out.end()) out.push_back(i);
  }
  if (out.empty()) throw InputError("--input names no input");
  return out;
}

std::vector<CampaignInput> campaign_inputs(const Model& m, double amplitude_pct, double scale) {
  if (!(scale > 0)) throw InputError("--amplitude-scale must be > 0");
  std::vector<CampaignInput> v;
  for (const auto& in : m.inputs) {
    double pct =
        scale * (amplitude_pct >= 0 ? amplitude_pct
                                    : (in.test_amplitude_pct > 0 ? in.test_amplitude_pct : 2.0));
    if (!(pct > 0) || pct > 50)
      throw InputError("amplitude " + std::to_string(pct) + " % of full scale must be in (0, 50]");
    double rate = 0;
    for (const auto& nl : in.nonlinearity)
      if (nl.kind == NonlinearityKind::kRateLimit && nl.rate > 0)
        rate = rate > 0 ? std::min(rate, nl.rate) : nl.rate;
    v.push_back({in.name, m.dc(in.name), pct / 100.0 * in.full_scale, in.full_scale, rate});
  }
  return v;
}

}  // namespace fralab
