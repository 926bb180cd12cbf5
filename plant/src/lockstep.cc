#include "fralab/plant/lockstep.h"

#include "fralab/core/pair_id.h"

namespace fralab {

LockstepPlant::LockstepPlant(const Model& model, const SimulatorOptions& opt, std::string run_id)
    : sim_(model, opt), run_id_(std::move(run_id)) {
  for (const auto& in : model.inputs) input_names_.push_back(in.name);
}

bool LockstepPlant::accepts(const std::string& run_id) {
  if (run_id_.empty()) run_id_ = run_id;
  return run_id == run_id_;
}

Block LockstepPlant::advance(const Block& cmd) {
  if (cmd.seq != next_seq_) {
    throw InputError("command block gap: expected seq " + std::to_string(next_seq_) + ", got " +
                     std::to_string(cmd.seq) + " (a block was lost or reordered)");
  }
  if (cmd.start_sample != sim_.samples_done()) {
    throw InputError("command block seq " + std::to_string(cmd.seq) + " starts at sample " +
                     std::to_string(cmd.start_sample) + ", plant is at " +
                     std::to_string(sim_.samples_done()));
  }
  std::vector<int> idx;
  for (const auto& n : input_names_) {
    int c = cmd.channel_index(command_channel(n));
    if (c < 0) throw InputError("command block has no channel u_" + n);
    idx.push_back(c);
  }
  Block tape;
  tape.run_id = cmd.run_id;
  tape.seq = cmd.seq;
  tape.start_sample = cmd.start_sample;
  tape.sample_rate_hz = cmd.sample_rate_hz;
  tape.final_block = cmd.final_block;
  tape.n_samples = cmd.n_samples;
  std::vector<int> echo;
  for (const auto& n : input_names_) tape.channels.push_back(command_channel(n));
  for (const auto& n : sim_.channel_names()) tape.channels.push_back(n);
  for (size_t c = 0; c < cmd.channels.size(); ++c) {
    if (!commanded_input(cmd.channels[c])) {
      echo.push_back(static_cast<int>(c));
      tape.channels.push_back(cmd.channels[c]);
    }
  }
  tape.samples.assign(tape.channels.size() * size_t(cmd.n_samples), 0.0);
  std::vector<double> u(input_names_.size()), y(sim_.n_channels());
  const int ni = static_cast<int>(input_names_.size());
  for (int k = 0; k < cmd.n_samples; ++k) {
    for (int i = 0; i < ni; ++i) u[i] = cmd.at(idx[i], k);
    sim_.step(u.data(), y.data());
    for (int i = 0; i < ni; ++i) tape.at(i, k) = u[i];
    for (size_t c = 0; c < y.size(); ++c) tape.at(ni + int(c), k) = y[c];
    for (size_t e = 0; e < echo.size(); ++e)
      tape.at(ni + int(y.size() + e), k) = cmd.at(echo[e], k);
  }
  ++next_seq_;
  if (cmd.final_block) done_ = true;
  return tape;
}

Block LockstepPlant::hold(const Block& abort) {
  Block cmd = abort;
  cmd.seq = next_seq_;
  cmd.start_sample = sim_.samples_done();
  Block tape = advance(cmd);
  tape.seq = -1;
  done_ = true;
  return tape;
}

void LockstepPlant::replay(const Block& rec) {
  Block cmd;
  cmd.run_id = rec.run_id;
  cmd.seq = rec.seq;
  cmd.start_sample = rec.start_sample;
  cmd.sample_rate_hz = rec.sample_rate_hz;
  cmd.n_samples = rec.n_samples;
  cmd.final_block = rec.final_block;
  const size_t ni = input_names_.size(), first_echo = ni + size_t(sim_.n_channels());
  if (rec.channels.size() < first_echo)
    throw InputError("tape block seq " + std::to_string(rec.seq) +
                     " has fewer channels than this plant makes: not this model's tape");
  for (size_t c = 0; c < rec.channels.size(); ++c) {
    if (c >= ni && c < first_echo) continue;
    cmd.channels.push_back(rec.channels[c]);
    cmd.samples.insert(cmd.samples.end(), rec.samples.begin() + c * size_t(rec.n_samples),
                       rec.samples.begin() + (c + 1) * size_t(rec.n_samples));
  }
  const Block again = advance(cmd);
  if (again.channels != rec.channels)
    throw InputError("tape block seq " + std::to_string(rec.seq) +
                     ": its channels are not the ones this plant makes: not this model's tape");
  for (size_t c = 0; c < again.channels.size(); ++c)
    for (int k = 0; k < again.n_samples; ++k)
      if (again.at(int(c), k) != rec.at(int(c), k))
        throw InputError("tape block seq " + std::to_string(rec.seq) + ", channel " +
                         again.channels[c] + ", sample " + std::to_string(rec.start_sample + k) +
                         ": the plant does not make the recorded value again (" +
                         std::to_string(again.at(int(c), k)) + " vs " +
                         std::to_string(rec.at(int(c), k)) +
                         "): another model, seed or sample rate than the recorded run");
}

}  // namespace fralab
