#include "fralab/identify/stabilisation.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "fralab/analyze/bode_plot.h"
#include "fralab/core/error.h"
#include "fralab/identify/pole_set_fit.h"

namespace fralab {

namespace {

using C = std::complex<double>;

double zeta_of(C p) { return -p.real() / std::abs(p); }
double hz(C p) { return std::abs(p) / (2 * std::numbers::pi); }

bool near_in_frequency(C a, C b, const StabilisationOptions& o) {
  return a.imag() > 0 && b.imag() > 0 &&
         std::abs(std::abs(a) - std::abs(b)) <= o.frequency_rel * std::abs(a);
}

bool near(C a, C b, const StabilisationOptions& o) {
  return near_in_frequency(a, b, o) &&
         std::abs(zeta_of(a) - zeta_of(b)) <= o.damping_rel * zeta_of(a);
}

}  // namespace

void StabilisationOptions::validate() const {
  auto bad = [](const std::string& m) { throw InputError("stabilisation diagram: " + m); };
  if (max_pairs < 1 || max_pairs > 200) bad("max_pairs must be in [1, 200]");
  if (relocations < 1) bad("relocations must be >= 1");
  if (!(frequency_rel > 0 && frequency_rel < 1)) bad("frequency_rel must be in (0, 1)");
  if (!(damping_rel > 0)) bad("damping_rel must be > 0");
  if (!(max_zeta > 0 && max_zeta <= 1)) bad("max_zeta must be in (0, 1]");
  if (min_stable_rows < 1) bad("min_stable_rows must be >= 1");
}

const char* to_string(PoleStability s) {
  switch (s) {
    case PoleStability::kStable:
      return "stable";
    case PoleStability::kFrequency:
      return "frequency";
    case PoleStability::kNew:
      break;
  }
  return "new";
}

StabilisationDiagram stabilisation_diagram(const std::vector<double>& w,
                                           const std::vector<std::vector<C>>& g,
                                           const std::vector<std::vector<double>>& W,
                                           const StabilisationOptions& o) {
  o.validate();
  StabilisationDiagram d;
  if (w.empty()) return d;
  d.w_lo = w.front(), d.w_hi = w.back();
  for (int n = 1; n <= o.max_pairs; ++n) {
    StabilisationRow row;
    row.pairs = n;
    row.poles = relocated_poles(w, g, W, n, o.relocations);
    if (row.poles.empty()) break;
    std::sort(row.poles.begin(), row.poles.end(),
              [](C a, C b) { return std::abs(a) < std::abs(b); });
    for (C p : row.poles) {
      PoleStability s = PoleStability::kNew;
      if (!d.rows.empty()) {
        for (C q : d.rows.back().poles) {
          if (near(p, q, o)) {
            s = PoleStability::kStable;
            break;
          }
          if (near_in_frequency(p, q, o)) s = PoleStability::kFrequency;
        }
      }
      row.stability.push_back(s);
    }
    d.rows.push_back(std::move(row));
  }
  return d;
}

int stable_rows(const StabilisationDiagram& d, C p, const StabilisationOptions& o) {
  int n = 0;
  for (const StabilisationRow& r : d.rows)
    n += std::any_of(r.poles.begin(), r.poles.end(), [&](C q) { return near(p, q, o); }) ? 1 : 0;
  return n;
}

bool physical_pole(const StabilisationDiagram& d, C p, const StabilisationOptions& o) {
  return p.imag() > 0 && zeta_of(p) <= o.max_zeta && std::abs(p) >= d.w_lo &&
         std::abs(p) <= d.w_hi && stable_rows(d, p, o) >= o.min_stable_rows;
}

Json stabilisation_to_json(const StabilisationDiagram& d) {
  Json j;
  j["band_hz"] = {d.w_lo / (2 * std::numbers::pi), d.w_hi / (2 * std::numbers::pi)};
  j["rows"] = Json::array();
  for (const StabilisationRow& r : d.rows) {
    Json rj{{"pairs", r.pairs}, {"poles", Json::array()}};
    for (size_t k = 0; k < r.poles.size(); ++k)
      rj["poles"].push_back({{"f_hz", hz(r.poles[k])},
                             {"zeta", zeta_of(r.poles[k])},
                             {"stability", to_string(r.stability[k])}});
    j["rows"].push_back(rj);
  }
  return j;
}

bool render_stabilisation_diagram(const StabilisationDiagram& d, const std::vector<C>& physical,
                                  const std::vector<double>& w,
                                  const std::vector<std::vector<C>>& g, const std::string& png) {
  namespace fs = std::filesystem;
  const fs::path out(png);
  const fs::path dir = out.has_parent_path() ? out.parent_path() : fs::path(".");
  fs::create_directories(dir);
  const std::string stem = out.stem().string();
  const fs::path poles_dat = dir / (stem + "_poles.dat"), curves_dat = dir / (stem + "_curves.dat"),
                 script = dir / (stem + ".gp");
  {
    // Columns: f_hz, pairs, class (0 new, 1 frequency, 2 stable); in the band only.
    std::ofstream f(poles_dat);
    for (const StabilisationRow& r : d.rows)
      for (size_t k = 0; k < r.poles.size(); ++k)
        if (r.poles[k].imag() > 0 && std::abs(r.poles[k]) >= d.w_lo &&
            std::abs(r.poles[k]) <= d.w_hi)
          f << hz(r.poles[k]) << ' ' << r.pairs << ' ' << int(r.stability[k]) << '\n';
  }
  {
    std::ofstream f(curves_dat);
    std::vector<double> top(g.size(), 1e-300);
    for (size_t c = 0; c < g.size(); ++c)
      for (C v : g[c]) top[c] = std::max(top[c], std::abs(v));
    for (size_t i = 0; i < w.size(); ++i) {
      f << w[i] / (2 * std::numbers::pi);
      for (size_t c = 0; c < g.size(); ++c)
        f << ' ' << 20 * std::log10(std::max(std::abs(g[c][i]) / top[c], 1e-300));
      f << '\n';
    }
  }
  const int rows = d.rows.empty() ? 1 : d.rows.back().pairs;
  std::ofstream gp(script);
  gp << "set terminal pngcairo size 1000,700 font ',10'\nset output '" << out.string() << "'\n"
     << "set termoption noenhanced\nset title 'stabilisation diagram: " << physical.size()
     << " physical modes (lines)'\nset xlabel 'frequency (Hz)'\nset ylabel 'model order (pairs)'\n"
     << "set y2label 'magnitude over its largest (dB)'\nset ytics nomirror\nset y2tics\n"
     << "set xrange [" << d.w_lo / (2 * std::numbers::pi) << ":" << d.w_hi / (2 * std::numbers::pi)
     << "]\nset yrange [0:" << rows + 1 << "]\n"
     << "set key outside bottom center horizontal\n";
  for (C p : physical)
    gp << "set arrow from " << hz(p) << ", graph 0 to " << hz(p)
       << ", graph 1 nohead lc rgb '#bbbbbb' dt 2\n";
  gp << "plot '" << poles_dat.string()
     << "' using 1:($3==0?$2:1/0) with points pt 6 ps 0.6 lc rgb '#999999' title 'new', '"
     << poles_dat.string()
     << "' using 1:($3==1?$2:1/0) with points pt 2 ps 0.7 lc rgb '#1f77b4' title 'frequency "
        "stable', '"
     << poles_dat.string()
     << "' using 1:($3==2?$2:1/0) with points pt 7 ps 0.6 lc rgb '#d62728' title 'stable'";
  for (size_t c = 0; c < g.size(); ++c)
    gp << ", '" << curves_dat.string() << "' using 1:" << c + 2
       << " axes x1y2 with lines lw 1 title 'curve " << c + 1 << "'";
  gp << "\n";
  gp.close();
  return run_gnuplot(script.string());
}

}  // namespace fralab
