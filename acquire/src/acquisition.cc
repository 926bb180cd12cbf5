#include "fralab/acquire/acquisition.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "fralab/acquire/model_info.h"
#include "fralab/core/pair_id.h"

namespace fralab {

const char* to_string(Excitation e) {
  switch (e) {
    case Excitation::kStepped:
      return "stepped";
    case Excitation::kSweep:
      return "sweep";
    case Excitation::kMultisine:
      return "multisine";
  }
  return "?";
}

Excitation excitation_from_string(const std::string& s) {
  for (Excitation e : {Excitation::kStepped, Excitation::kSweep, Excitation::kMultisine})
    if (s == to_string(e)) return e;
  throw InputError("--excitation \"" + s + "\": stepped, sweep or multisine");
}

void AcquireOptions::validate() const {
  if (block < 0) throw InputError("--block must be >= 1 (or 0: sized to the sample rate)");
  if (window < 1) throw InputError("--window must be >= 1");
  if (!(speed >= 0)) throw InputError("--speed must be >= 0");
  if (free_running && !(speed > 0))
    throw InputError("--free-running needs --speed > 0 (the plant runs on its own clock)");
  if (free_running && excitation != Excitation::kStepped)
    throw InputError("--free-running repeats the steps an underrun touches: stepped sine only");
  if (lead < 1) throw InputError("--lead must be >= 1");
  if (max_repeats < 0) throw InputError("--max-repeats must be >= 0");
  if (!(amplitude_scale > 0)) throw InputError("--amplitude-scale must be > 0");
  if (multisine_phases != "schroeder" && multisine_phases != "random" &&
      multisine_phases != "low-crest")
    throw InputError("--multisine-phases \"" + multisine_phases +
                     "\": schroeder, random or low-crest");
  parse_band(band);
  adaptive.validate();
  if (adaptive.enabled() && (excitation != Excitation::kStepped || free_running))
    throw InputError(
        "--sigma-target: the adaptive stepped sine needs --excitation stepped, in "
        "lockstep (not --free-running)");
  if (!adaptive.enabled() && !adaptive_decided.empty())
    throw InputError("--adaptive-decided without --sigma-target");
  parse_decisions(adaptive_decided);
  if (!zoom.empty() && excitation != Excitation::kMultisine)
    throw InputError("--zoom places a multisine's lines: it needs --excitation multisine or auto");
  MultisineOptions zoomed;  // the zoom's own checks, on the defaults' band
  zoomed.zoom = zoom;
  zoomed.zoom_period_factor = zoom_period_factor;
  zoomed.validate();
}

SteppedSineOptions stepped_sine_options(const Model& model, const AcquireOptions& o) {
  SteppedSineOptions so;
  std::tie(so.f_lo_hz, so.f_hi_hz) = parse_band(o.band);
  so.points_per_decade = o.points_per_decade;
  so.min_cycles = o.min_cycles;
  so.min_integrate_s = o.min_integrate_s;
  so.settle_cycles = o.settle_cycles;
  so.sample_rate_hz = o.sample_rate_hz;
  so.slowest_time_constant_s =
      o.slowest_time_constant_s >= 0 ? o.slowest_time_constant_s : slowest_time_constant_s(model);
  return so;
}

std::unique_ptr<Campaign> make_campaign(const Model& model, const AcquireOptions& o,
                                        const std::string& run_id) {
  o.validate();
  const SteppedSineOptions so = stepped_sine_options(model, o);
  const int block = block_samples(model, o);
  const std::vector<int> excite = select_inputs(model, o.inputs);
  auto cin = campaign_inputs(model, o.amplitude_pct, o.amplitude_scale);
  switch (o.excitation) {
    case Excitation::kStepped:
      if (o.adaptive.enabled())
        return std::make_unique<AdaptiveSineCampaign>(cin, excite, so, o.adaptive.pilot_cycles,
                                                      block, run_id,
                                                      parse_decisions(o.adaptive_decided));
      return std::make_unique<SteppedSineCampaign>(cin, excite, plan_stepped_sine(so),
                                                   so.sample_rate_hz, run_id);
    case Excitation::kSweep:
      return std::make_unique<SweepCampaign>(cin, excite, so, run_id);
    case Excitation::kMultisine:
      return std::make_unique<MultisineCampaign>(cin, excite, multisine_options(model, o), run_id);
  }
  throw InputError("unknown excitation");
}

MultisineOptions multisine_options(const Model& model, const AcquireOptions& o) {
  const SteppedSineOptions so = stepped_sine_options(model, o);
  MultisineOptions mo;
  mo.f_lo_hz = so.f_lo_hz;
  mo.f_hi_hz = so.f_hi_hz;
  mo.points_per_decade = so.points_per_decade;
  mo.periods = std::max(2, so.min_cycles);
  mo.slowest_time_constant_s = so.slowest_time_constant_s;
  mo.sample_rate_hz = so.sample_rate_hz;
  mo.odd_lines = o.odd_lines;
  mo.phases = o.multisine_phases;
  mo.design = o.multisine_design;
  mo.realisations = o.realisations;
  mo.zoom = o.zoom;
  mo.zoom_period_factor = o.zoom_period_factor;
  return mo;
}

std::vector<ZoomPlacement> zoom_placement(const Model& model, const AcquireOptions& o) {
  if (o.excitation != Excitation::kMultisine || o.zoom.empty()) return {};
  const MultisineOptions mo = multisine_options(model, o);
  const int P = multisine_period_samples(mo);
  return zoom_placement(mo, P, multisine_lines(mo, P));
}

std::unique_ptr<AutoIntegrator> make_auto_integrator(Campaign& c, const Model& m,
                                                     const AcquireOptions& o,
                                                     int64_t first_sample) {
  auto* adaptive = dynamic_cast<AdaptiveSineCampaign*>(&c);
  if (!adaptive) return nullptr;
  std::vector<std::string> outputs;
  for (const auto& out : m.outputs) outputs.push_back(out.name);
  return std::make_unique<AutoIntegrator>(*adaptive, outputs, o.adaptive, first_sample);
}

int block_samples(const Model& model, const AcquireOptions& o) {
  const double bytes_per_sample = 8.0 * double(model.inputs.size() * 2 + model.outputs.size() + 2);
  const int most = int(std::floor(kMaxTapeBlockBytes / bytes_per_sample));
  if (o.block > 0) {
    if (o.block > most)
      throw InputError("--block " + std::to_string(o.block) + " would make tape blocks over " +
                       std::to_string(int(kMaxTapeBlockBytes / 1000)) +
                       " kB (LCM fragments); at most " + std::to_string(most) + " samples for " +
                       model.name);
    return o.block;
  }
  const int half_second = int(std::lround(0.5 * o.sample_rate_hz));
  return std::max(1, std::min(half_second, most));
}

void require_sized_block(int block, const std::string& what) {
  if (block < 1)
    throw InputError(what + ": blocks of " + std::to_string(block) +
                     " samples; size the block first (block_samples)");
}

int64_t command_block_count(const Campaign& c, int block) {
  require_sized_block(block, "command blocks");
  return (c.total_samples() + block - 1) / block;
}

Block abort_block(const Campaign& c, int64_t seq, int64_t start_sample, int n,
                  double sample_rate_hz, const std::string& run_id) {
  Block blk;
  blk.run_id = run_id;
  blk.seq = seq;
  blk.start_sample = start_sample;
  blk.sample_rate_hz = sample_rate_hz;
  blk.n_samples = n;
  blk.final_block = true;
  for (const auto& in : c.inputs()) {
    blk.channels.push_back(command_channel(in.name));
    blk.samples.insert(blk.samples.end(), size_t(n), in.dc);
  }
  blk.channels.push_back("ref_phase");
  blk.channels.push_back("ref_freq_hz");
  blk.samples.insert(blk.samples.end(), 2 * size_t(n), 0.0);
  return blk;
}

Block command_block(const Campaign& c, int64_t seq, int block, double sample_rate_hz,
                    const std::string& run_id) {
  require_sized_block(block, "command block");
  const int64_t s0 = seq * block;
  const int n = int(std::min<int64_t>(block, c.total_samples() - s0));
  std::vector<std::vector<double>> cmd;
  std::vector<double> ref_phase, ref_freq;
  c.fill(s0, n, cmd, ref_phase, ref_freq);
  Block blk;
  blk.run_id = run_id;
  blk.seq = seq;
  blk.start_sample = s0;
  blk.sample_rate_hz = sample_rate_hz;
  blk.n_samples = n;
  blk.final_block = seq == command_block_count(c, block) - 1;
  for (const auto& in : c.inputs()) blk.channels.push_back(command_channel(in.name));
  blk.channels.push_back("ref_phase");
  blk.channels.push_back("ref_freq_hz");
  blk.samples.reserve(blk.channels.size() * n);
  for (const auto& v : cmd) blk.samples.insert(blk.samples.end(), v.begin(), v.end());
  blk.samples.insert(blk.samples.end(), ref_phase.begin(), ref_phase.end());
  blk.samples.insert(blk.samples.end(), ref_freq.begin(), ref_freq.end());
  return blk;
}

}  // namespace fralab
