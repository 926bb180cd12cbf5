#include "fralab/lab/monitor.h"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace fralab {

std::string monitor_header(bool with_simulation) {
  char b[256];
  std::snprintf(b, sizeof b, "%-11s %-12s %-10s", "f_hz", "mag", "phase_deg");
  std::string h = b;
  if (with_simulation) {
    std::snprintf(b, sizeof b, " |  %-12s %-10s |  %-8s %-7s", "sim_mag", "sim_deg", "d_dB",
                  "d_deg");
    h += b;
  }
  return h + "  sigma";
}

std::string monitor_row(const FrdPoint& p, const std::optional<std::complex<double>>& sim) {
  char b[256];
  const double f = p.w / (2 * std::numbers::pi);
  if (!p.valid) {
    std::snprintf(b, sizeof b, "%-11.4g invalid: %s", f, p.note.c_str());
    return b;
  }
  std::snprintf(b, sizeof b, "%-11.4g %-12.6g %-10.2f", f, p.mag, p.phase_deg);
  std::string row = b;
  if (sim) {
    const double sm = std::abs(*sim), sd = std::arg(*sim) * 180 / std::numbers::pi;
    const double dd = std::remainder(p.phase_deg - sd, 360.0);
    std::snprintf(b, sizeof b, " |  %-12.6g %-10.2f |  %+-8.2f %+-7.1f", sm, sd,
                  20 * std::log10(p.mag / sm), dd);
    row += b;
  }
  if (p.sigma > 0) {
    std::snprintf(b, sizeof b, "  %.3g", p.sigma);
    row += b;
  }
  return row;
}

}  // namespace fralab
