#include "fralab/analyze/bode_plot.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "fralab/core/tf.h"

namespace fralab {

bool render_bode_plots(const std::vector<BodePlot>& plots, const std::string& dir,
                       const std::string& script) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  static const char* kColour[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd"};
  static const char* kResidual[] = {"#ff7f0e", "#17becf", "#98df8a", "#c5b0d5"};
  auto db = [](std::complex<double> v) { return 20 * std::log10(std::max(std::abs(v), 1e-300)); };
  auto deg = [](std::complex<double> v) { return std::arg(v) * 180 / std::numbers::pi; };
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,900 font 'sans,10'\nset termoption noenhanced\nset "
        "logscale x\nset grid\nset key bottom left\n";
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
    gp << "set output '" << dir << "/" << p.stem << ".png'\nset multiplot layout 3,1 title '"
       << p.title << "'\n"
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
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) return false;
  return std::system(("gnuplot '" + dir + "/" + script + "' >/dev/null 2>&1").c_str()) == 0;
}

}  // namespace fralab
