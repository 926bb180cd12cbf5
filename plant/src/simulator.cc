#include "fralab/plant/simulator.h"

#include <algorithm>
#include <cmath>

#include "fralab/core/text.h"

namespace fralab {

void SimulatorOptions::validate() const {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    throw InputError("sample rate must be a positive number of Hz, got " +
                     std::to_string(sample_rate_hz));
  }
}

Simulator::Simulator(const Model& model, const SimulatorOptions& options)
    : model_(model), opt_(options) {
  opt_.validate();
  const double h = 1.0 / opt_.sample_rate_hz;
  auto where = [&](const std::string& what) { return model_.source + ": " + what + ": "; };
  for (const ModelInput& in : model_.inputs) {
    InputChain c;
    c.dc = model_.dc(in.name);
    try {
      if (in.actuator) c.actuator = std::make_unique<FohLti>(*in.actuator, h);
      for (const auto& s : in.nonlinearity) c.nl.push_back(make_nonlinearity(s, c.dc, h));
    } catch (const InputError& e) {
      throw InputError(where("actuator of " + in.name) + e.what());
    }
    c.noise = opt_.noise ? in.noise_rms : 0.0;
    for (const auto& m : in.measurement_coupling)
      c.coupling.emplace_back(model_.output_index(m.output), m.gain);
    for (const ChannelFault& f : in.faults) {
      if (f.kind != ChannelFaultKind::kStuck) continue;
      const auto from = int64_t(std::llround(f.from_s * opt_.sample_rate_hz));
      const double to = std::min(9e18, (f.from_s + f.for_s) * opt_.sample_rate_hz);
      c.stuck.emplace_back(from, int64_t(std::llround(to)));
    }
    names_.push_back(in.name);
    inputs_.push_back(std::move(c));
  }
  for (const ModelOutput& out : model_.outputs) {
    names_.push_back(out.name);
    out_dc_.push_back(model_.dc(out.name));
    out_noise_.push_back(opt_.noise ? out.noise_rms : 0.0);
  }
  for (const ModelPath& p : model_.paths) {
    PathChain pc;
    pc.input = model_.input_index(p.input);
    pc.output = model_.output_index(p.output);
    const ModelInput& in = model_.inputs[pc.input];
    // A stuck actuator is a nonlinearity of its position too: the paths follow the position.
    pc.from_position = !in.nonlinearity.empty() || !inputs_[pc.input].stuck.empty();
    Tf chain = p.tf;
    if (!pc.from_position && in.actuator) chain = *in.actuator * chain;
    const auto& sensor = model_.outputs[pc.output].sensor;
    if (sensor) chain = chain * *sensor;
    try {
      pc.lti = std::make_unique<FohLti>(chain, h);
    } catch (const InputError& e) {
      throw InputError(where("path " + p.input + " -> " + p.output) + e.what());
    }
    paths_.push_back(std::move(pc));
  }
  // Outputs without paths still get their sensor dynamics trivially (constant); nothing to build.
  for (size_t c = 0; c < names_.size(); ++c) {
    std::seed_seq seq{static_cast<uint32_t>(opt_.seed), static_cast<uint32_t>(opt_.seed >> 32),
                      static_cast<uint32_t>(c), 0x6672616cU};
    rng_.emplace_back(seq);
  }
  for (size_t c = 0; c < names_.size(); ++c) {
    const bool is_input = c < model_.inputs.size();
    const auto& faults =
        is_input ? model_.inputs[c].faults : model_.outputs[c - model_.inputs.size()].faults;
    std::vector<ChannelFault> own;
    for (const ChannelFault& f : faults) {
      if (f.kind == ChannelFaultKind::kSwap) swaps_.emplace_back(int(c), index_of(names_, f.with));
      if (f.kind != ChannelFaultKind::kSwap && f.kind != ChannelFaultKind::kStuck) own.push_back(f);
    }
    faulty_.emplace_back(std::move(own), model_.dc(names_[c]), opt_.sample_rate_hz, opt_.seed,
                         int(c));
  }
  du_.assign(inputs_.size(), 0.0);
  pos_.assign(inputs_.size(), 0.0);
  out_.assign(model_.outputs.size(), 0.0);
}

void Simulator::reset() {
  for (auto& c : inputs_) {
    if (c.actuator) c.actuator->reset();
    for (auto& n : c.nl) n->reset();
  }
  for (auto& p : paths_) p.lti->reset();
  for (auto& f : faulty_) f.reset();
  k_ = 0;
}

void Simulator::step(const double* commands, double* channels) {
  const size_t ni = inputs_.size();
  for (size_t i = 0; i < ni; ++i) {
    if (!std::isfinite(commands[i])) {
      throw InputError("command for input " + names_[i] + " at sample " + std::to_string(k_) +
                       " is not a finite number");
    }
    InputChain& c = inputs_[i];
    du_[i] = commands[i] - c.dc;
    double p = c.actuator ? c.actuator->step(du_[i]) : du_[i];
    for (auto& n : c.nl) p = n->apply(p);
    for (const auto& [from, to] : c.stuck) {
      if (k_ == from) c.held = k_ > 0 ? pos_[i] : p;
      if (k_ >= from && k_ < to) p = c.held;
    }
    pos_[i] = p;
  }
  std::fill(out_.begin(), out_.end(), 0.0);
  for (PathChain& pc : paths_) {
    out_[pc.output] += pc.lti->step(pc.from_position ? pos_[pc.input] : du_[pc.input]);
  }
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (size_t i = 0; i < ni; ++i) {
    double v = pos_[i];
    for (const auto& [o, g] : inputs_[i].coupling) v += g * out_[o];
    double noise = inputs_[i].noise > 0.0 ? inputs_[i].noise * gauss(rng_[i]) : 0.0;
    channels[i] = faulty_[i].empty() ? inputs_[i].dc + v + noise
                                     : faulty_[i].apply(k_, inputs_[i].dc + v, noise);
  }
  for (size_t o = 0; o < out_.size(); ++o) {
    double noise = out_noise_[o] > 0.0 ? out_noise_[o] * gauss(rng_[ni + o]) : 0.0;
    channels[ni + o] = faulty_[ni + o].empty()
                           ? out_dc_[o] + out_[o] + noise
                           : faulty_[ni + o].apply(k_, out_dc_[o] + out_[o], noise);
  }
  for (const auto& [a, b] : swaps_) std::swap(channels[a], channels[b]);
  ++k_;
}

MeasurementChain emulator_chain(const Model& m, double sample_rate_hz) {
  MeasurementChain c;
  c.sample_rate_hz = sample_rate_hz;
  c.hold = MeasurementChain::Hold::kFirstOrder;
  for (const auto& in : m.inputs)
    if (!in.nonlinearity.empty()) c.reheld_inputs.push_back(in.name);
  return c;
}

}  // namespace fralab
