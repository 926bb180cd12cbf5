#include "fralab/analyze/bode_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "fralab/core/tf.h"

namespace fralab {

namespace {

const char* kColour[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd"};
const char* kResidual[] = {"#ff7f0e", "#17becf", "#98df8a", "#c5b0d5"};

std::string terminal(PlotFormat f, int width, int height, int font) {
  std::ostringstream s;
  s << (f == PlotFormat::kSvg ? "set terminal svg size " : "set terminal pngcairo size ") << width
    << "," << height << " font 'sans," << font << "'\n";
  return s.str();
}

const char* extension(PlotFormat f) { return f == PlotFormat::kSvg ? ".svg" : ".png"; }

}  // namespace

bool run_gnuplot(const std::string& script_path) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) return false;
  std::string quoted = "'";  // the path in single quotes, a quote in it as '\''
  for (char c : script_path) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return std::system(("gnuplot " + quoted + "' >/dev/null 2>&1").c_str()) == 0;
}

bool render_bode_plots(const std::vector<BodePlot>& plots, const std::string& dir,
                       const std::string& script, PlotFormat format) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  auto db = [](std::complex<double> v) { return 20 * std::log10(std::max(std::abs(v), 1e-300)); };
  auto deg = [](std::complex<double> v) { return std::arg(v) * 180 / std::numbers::pi; };
  std::ostringstream gp;
  gp << terminal(format, 900, 900, 10)
     << "set termoption noenhanced\nset logscale x\nset grid\nset key bottom left\n";
  for (const auto& p : plots) {
    const size_t N = p.w.size();
    bool ok = p.meas.size() == N && (p.sigma.empty() || p.sigma.size() == N);
    for (const auto& m : p.models) ok = ok && m.g.size() == N;
    if (!ok)
      throw InputError("bode plot " + p.stem +
                       ": frequencies, measurements, sigmas and model curves differ in length");
    if (p.models.size() > 4) {
      throw InputError("bode plot " + p.stem + ": " + std::to_string(p.models.size()) +
                       " model curves, at most 4 are drawn");
    }
    const std::string dat = dir + "/" + p.stem + ".dat";
    std::ofstream out(dat);
    out.precision(12);
    // Columns: f, meas dB, sigma dB, meas deg, sigma deg, then per model: dB, deg, residual dB,
    // residual deg.
    double prev = 0.0;
    for (size_t i = 0; i < N; ++i) {
      const double rel = p.sigma.empty() ? 0.0 : p.sigma[i] / std::abs(p.meas[i]);
      const double pm = prev + std::remainder(deg(p.meas[i]) - prev, 360.0);  // unwrapped along f
      prev = pm;
      out << p.w[i] / (2 * std::numbers::pi) << " " << db(p.meas[i]) << " "
          << 20 / std::log(10.0) * rel << " " << pm << " " << rel * 180 / std::numbers::pi;
      for (const auto& m : p.models) {
        const auto r = p.meas[i] / m.g[i];
        out << " " << db(m.g[i]) << " " << pm + std::remainder(deg(m.g[i]) - pm, 360.0) << " "
            << db(r) << " " << deg(r);
      }
      out << "\n";
    }
    auto curves = [&](int first) {  // first: 0 gain, 1 phase (model columns 6 + 4k + first)
      std::ostringstream s;
      for (size_t k = 0; k < p.models.size(); ++k) {
        s << ", '' u 1:" << 6 + 4 * k + first << " w l lw 2" << (k ? " dt 2" : "") << " lc rgb '"
          << kColour[k] << "' t '" << p.models[k].title << "'";
      }
      return s.str();
    };
    const std::string bars = p.sigma.empty() ? "w lp pt 7 ps 0.5" : "w yerrorbars pt 7 ps 0.5";
    gp << "set output '" << dir << "/" << p.stem << extension(format)
       << "'\nset multiplot layout 3,1 title '" << p.title << "'\n"
       << "set ylabel 'gain (dB)'\nunset xlabel\nplot '" << dat << "' u 1:2"
       << (p.sigma.empty() ? "" : ":3") << " " << bars << " lc rgb 'black' t 'measured'"
       << curves(0) << "\n"
       << "set ylabel 'phase (deg)'\nset xlabel 'frequency (Hz)'\nplot '" << dat << "' u 1:4"
       << (p.sigma.empty() ? "" : ":5") << " " << bars << " lc rgb 'black' t 'measured'"
       << curves(1) << "\n"
       << "set ylabel 'residual (dB, deg)'\nplot ";
    for (size_t k = 0; k < p.models.size(); ++k) {
      gp << (k ? ", " : "") << "'" << dat << "' u 1:" << 8 + 4 * k << " w lp pt 7 ps 0.5"
         << (k ? " dt 2" : "") << " lc rgb '" << kColour[k] << "' t 'measured/" << p.models[k].title
         << " dB', '' u 1:" << 9 + 4 * k << " w lp pt 5 ps 0.5" << (k ? " dt 3" : "") << " lc rgb '"
         << kResidual[k] << "' t 'measured/" << p.models[k].title << " deg'";
    }
    if (p.models.empty()) gp << "0 t ''";
    gp << "\nunset multiplot\n";
  }
  std::ofstream(dir + "/" + script) << gp.str();
  return run_gnuplot(dir + "/" + script);
}

bool render_bode_overview(const std::vector<std::vector<const BodePlot*>>& grid,
                          const std::vector<std::string>& rows,
                          const std::vector<std::string>& cols, const std::string& title,
                          const std::string& dir, const std::string& stem, PlotFormat format) {
  bool ok = grid.size() == rows.size() && !rows.empty() && !cols.empty();
  for (const auto& r : grid) ok = ok && r.size() == cols.size();
  if (!ok)
    throw InputError("bode overview " + stem + ": the grid is not " + std::to_string(rows.size()) +
                     " x " + std::to_string(cols.size()));
  const int w = std::max(int(cols.size()) * 240, 480), h = int(rows.size()) * 2 * 130 + 80;
  std::ostringstream gp;
  gp << terminal(format, w, h, 8) << "set termoption noenhanced\nset output '" << dir << "/" << stem
     << extension(format) << "'\nset logscale x\nset grid\nunset key\n"
     << "set multiplot layout " << 2 * rows.size() << "," << cols.size() << " title '" << title
     << "'\nset lmargin 7\nset rmargin 1\nset tmargin 1.2\nset bmargin 1.2\nset format x ''\n";
  for (size_t r = 0; r < rows.size(); ++r) {
    for (int part = 0; part < 2; ++part) {  // 0 gain, 1 phase
      for (size_t c = 0; c < cols.size(); ++c) {
        const BodePlot* p = grid[r][c];
        gp << "set title '" << (part == 0 ? rows[r] + "/" + cols[c] + " (dB)" : "(deg)")
           << "' offset 0,-0.8\n";
        const bool bottom = r + 1 == rows.size() && part == 1;  // frequency labels once
        gp << (bottom ? "set format x '%g'\nset xlabel 'Hz' offset 0,0.8\n"
                      : "set format x ''\nunset xlabel\n");
        if (!p) {
          gp << "set multiplot next\n";
          continue;
        }
        const std::string dat = dir + "/" + p->stem + ".dat";
        gp << "plot '" << dat << "' u 1:" << (part == 0 ? 2 : 4)
           << " w p pt 7 ps 0.6 lc rgb 'black'";
        for (size_t k = 0; k < p->models.size(); ++k)
          gp << ", '' u 1:" << 6 + 4 * k + part << " w l lw 1.5" << (k ? " dt 2" : "")
             << " lc rgb '" << kColour[k] << "'";
        gp << "\n";
      }
    }
  }
  gp << "unset multiplot\n";
  const std::string script = dir + "/" + stem + extension(format) + ".gp";
  std::ofstream(script) << gp.str();
  return run_gnuplot(script);
}

std::string inline_svg(const std::string& svg_file) {
  std::ifstream in(svg_file);
  std::ostringstream text;
  text << in.rdbuf();
  const std::string svg = text.str();
  const size_t at = svg.find("<svg");
  return at == std::string::npos ? std::string() : svg.substr(at);
}

}  // namespace fralab
