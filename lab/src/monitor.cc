#include "fralab/lab/monitor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "fralab/analyze/bode_plot.h"
#include "fralab/core/error.h"

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

bool write_monitor_page(
    const std::string& page, const std::string& title, const std::vector<FrdPoint>& points,
    const std::function<std::optional<std::complex<double>>(const FrdPoint&)>& sim, bool live,
    int refresh_s) {
  namespace fs = std::filesystem;
  const fs::path path(page);
  const fs::path dir = path.parent_path() / (path.stem().string() + ".plot");
  std::vector<FrdPoint> pts;
  for (const auto& p : points)
    if (p.valid) pts.push_back(p);
  std::sort(pts.begin(), pts.end(), [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  BodePlot plot{title, "pair", {}, {}, {}, {}};
  BodeCurve simulation{"simulation", {}};
  bool all_sim = !pts.empty(), all_sigma = !pts.empty();
  for (const auto& p : pts) {
    plot.w.push_back(p.w);
    plot.meas.push_back(p.value());
    plot.sigma.push_back(p.sigma);
    all_sigma = all_sigma && p.sigma > 0;
    const auto g = sim ? sim(p) : std::nullopt;
    all_sim = all_sim && g.has_value();
    simulation.g.push_back(g.value_or(0.0));
  }
  if (!all_sigma) plot.sigma.clear();
  if (all_sim) plot.models.push_back(simulation);
  std::string figure;
  bool drawn = false;
  if (!pts.empty()) {
    if (render_bode_plots({plot}, dir.string(), "plot.gp", PlotFormat::kSvg))
      figure = inline_svg((dir / "pair.svg").string());
    drawn = !figure.empty();
  }
  if (!drawn)
    figure = pts.empty() ? "<p>No point yet.</p>" : "<p>No plot: gnuplot is missing or failed.</p>";
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  if (live) html << "<meta http-equiv=\"refresh\" content=\"" << refresh_s << "\">\n";
  html << "<title>fralab monitor</title>\n<style>body{font-family:sans-serif;margin:1em}svg{max-"
          "width:100%;height:auto}</style>\n</head>\n<body>\n<p>"
       << pts.size() << " points" << (live ? " so far (the page reloads itself)" : ", complete")
       << "</p>\n"
       << figure << "\n</body>\n</html>\n";
  const fs::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << html.str();
    if (!out) throw InputError(tmp.string() + ": cannot be written");
  }
  fs::rename(tmp, path);
  return drawn;
}

}  // namespace fralab
