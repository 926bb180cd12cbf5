#include "fralab/lab/progress.h"

#include <cmath>
#include <cstdio>

namespace fralab {

void ProgressLine::on_status(const StatusEvent& e) {
  if (!(e.sample_rate_hz > 0)) return;
  seen_ = true;
  if (e.state == RunState::kStart) {
    total_s_ = double(e.n_samples) / e.sample_rate_hz;
    return;
  }
  done_s_ = std::max(done_s_, double(e.sample) / e.sample_rate_hz);
  if (e.state == RunState::kDone || e.state == RunState::kAbort) return;
  step_ = e.step + 1;
  n_steps_ = e.n_steps;
  freq_hz_ = e.frequency_hz;
  int excited = 0;
  for (size_t i = 0; i < e.inputs.size() && i < e.amplitudes.size(); ++i) {
    if (e.amplitudes[i] != 0) {
      if (excited++ == 0) input_ = e.inputs[i];
    }
  }
  if (excited > 1) input_ = "all";
}

std::string ProgressLine::line(double wall_s) const {
  if (!seen_) return "";
  auto clock = [](double s) {
    char b[32];
    const long t = long(std::lround(s));
    std::snprintf(b, sizeof b, "%ld:%02ld", t / 60, t % 60);
    return std::string(b);
  };
  char buf[256];
  const double left = std::max(0.0, total_s_ - done_s_);
  std::snprintf(buf, sizeof buf, "%-4s step %d/%d  %.3g Hz  engine %.0f/%.0f s (%.0f s left)",
                input_.c_str(), step_, n_steps_, freq_hz_, done_s_, total_s_, left);
  std::string out = buf;
  if (total_s_ > 0 && done_s_ >= 0.01 * total_s_)
    out += "  wall " + clock(wall_s * left / done_s_) + " left";
  out += "  re-sent " + std::to_string(resent_);
  return out;
}

}  // namespace fralab
