#include "diagnose_cmd.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <iomanip>
#include <sstream>

#include "fralab/identify/diagnose.h"
#include "fralab/plant/embedded_models.h"

namespace fralab {

namespace fs = std::filesystem;

namespace {

std::vector<MeasuredPair> read_measured(const std::string& dir) {
  if (!fs::exists(dir + "/frd")) throw InputError(dir + ": not a measure folder (no frd/ inside)");
  std::vector<MeasuredPair> v;
  for (const auto& e : fs::directory_iterator(dir + "/frd")) {
    if (e.path().extension() != ".json") continue;
    MeasuredPair m;
    m.frd = load_frd(e.path().string());
    m.pair = m.frd.pair;
    const std::string val = dir + "/validation/frd/" + e.path().filename().string();
    if (fs::exists(val)) m.validation = load_frd(val);
    v.push_back(m);
  }
  std::sort(v.begin(), v.end(), [](const MeasuredPair& a, const MeasuredPair& b) { return a.pair < b.pair; });
  if (v.empty()) throw InputError(dir + "/frd: no frd files");
  return v;
}

// One PNG per pair: gain (dB) and phase (deg) of measured (with sigma bars), simulation, extended.
bool render_plots(const Diagnosis& d, const std::string& dir) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) return false;
  fs::create_directories(dir + "/plots");
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,900 font 'sans,10'\nset termoption noenhanced\nset logscale x\nset grid\nset key bottom left\n";
  for (const auto& p : d.pairs) {
    const std::string stem = pair_file_stem(p.pair);
    std::ofstream dat(dir + "/plots/" + stem + ".dat");
    auto db = [](std::complex<double> v) { return 20 * std::log10(std::max(std::abs(v), 1e-300)); };
    auto deg = [](std::complex<double> v) { return std::arg(v) * 180 / std::numbers::pi; };
    double prev_pm = 0.0;
    for (size_t i = 0; i < p.w.size(); ++i) {
      const double f = p.w[i] / (2 * std::numbers::pi);
      const double sdb = 20 / std::log(10.0) * p.sigma[i] / std::abs(p.meas[i]);
      const double sdeg = p.sigma[i] / std::abs(p.meas[i]) * 180 / std::numbers::pi;
      // Phases unwrapped relative to the measurement, so the three curves stay comparable.
      const double pm = prev_pm + std::remainder(deg(p.meas[i]) - prev_pm, 360.0);  // unwrapped along f
      prev_pm = pm;
      const double ps = pm + std::remainder(deg(p.sim[i]) - pm, 360.0), pe = pm + std::remainder(deg(p.ext[i]) - pm, 360.0);
      // Residuals measured / model in dB and degrees (columns 10-13).
      const auto rs = p.meas[i] / p.sim[i], re = p.meas[i] / p.ext[i];
      dat << f << " " << db(p.meas[i]) << " " << sdb << " " << pm << " " << sdeg << " " << db(p.sim[i]) << " " << ps
          << " " << db(p.ext[i]) << " " << pe << " " << db(rs) << " " << deg(rs) << " " << db(re) << " " << deg(re) << "\n";
    }
    gp << "set output '" << dir << "/plots/" << stem << ".png'\nset multiplot layout 3,1 title '" << p.pair
       << " (response " << split_pair(p.pair).second << "/" << split_pair(p.pair).first << ")'\n"
       << "set ylabel 'gain (dB)'\nunset xlabel\nplot '" << dir << "/plots/" << stem
       << ".dat' u 1:2:3 w yerrorbars pt 7 ps 0.5 lc rgb 'black' t 'measured', '' u 1:6 w l lw 2 lc rgb '#d62728' t 'simulation', '' u 1:8 w l lw 2 dt 2 lc rgb '#1f77b4' t 'extended model'\n"
       << "set ylabel 'phase (deg)'\nset xlabel 'frequency (Hz)'\nplot '" << dir << "/plots/" << stem
       << ".dat' u 1:4:5 w yerrorbars pt 7 ps 0.5 lc rgb 'black' t 'measured', '' u 1:7 w l lw 2 lc rgb '#d62728' t 'simulation', '' u 1:9 w l lw 2 dt 2 lc rgb '#1f77b4' t 'extended model'\n"
       << "set ylabel 'residual (dB, deg)'\nplot '" << dir << "/plots/" << stem
       << ".dat' u 1:10 w lp pt 7 ps 0.5 lc rgb '#d62728' t 'measured/simulation dB', '' u 1:11 w lp pt 5 ps 0.5 lc rgb '#ff7f0e' t 'measured/simulation deg', '' u 1:12 w l lw 2 dt 2 lc rgb '#1f77b4' t 'measured/extended dB', '' u 1:13 w l lw 2 dt 3 lc rgb '#17becf' t 'measured/extended deg'\n"
       << "unset multiplot\n";
  }
  std::ofstream(dir + "/plots/plots.gp") << gp.str();
  return std::system(("gnuplot '" + dir + "/plots/plots.gp' >/dev/null 2>&1").c_str()) == 0;
}

void write_report(const Diagnosis& d, const std::string& sim_name, const std::string& data_name, bool plots,
                  const std::string& dir) {
  std::ofstream md(dir + "/report.md");
  md << "# Diagnosis: " << sim_name << "\n\nMeasured data: " << data_name << "\n\n";
  md << "Error (" << d.metric << "): simulation **" << std::setprecision(3) << d.error_before << "**, extended model **"
     << d.error_after << "**";
  if (d.validation_before >= 0) {
    md << "; on the independent validation measurement: " << d.validation_before << " -> " << d.validation_after;
  }
  md << ".\n\n## Findings\n\n";
  if (d.findings.empty()) md << "None: every measured response agrees with the simulation within its uncertainty.\n";
  for (const auto& f : d.findings) {
    md << "- **" << f.cause << "** (" << f.scope;
    if (!f.input.empty()) md << ", input " << f.input;
    if (!f.output.empty()) md << ", output " << f.output;
    md << "):";
    for (const auto& [k, v] : f.parameters) md << " " << k << " = " << v;
    for (const auto& [k, v] : f.text_parameters) md << " " << k << " = " << v;
    md << ". " << f.explanation << ". Error " << f.error_before << " -> " << f.error_after << " over ";
    for (size_t i = 0; i < f.pairs.size(); ++i) md << (i ? ", " : "") << f.pairs[i];
    md << ".\n";
  }
  md << "\n## Pairs\n\n| pair | beyond uncertainty | chi2 sim | chi2 extended | error sim | error extended |\n|---|---|---|---|---|---|\n";
  for (const auto& p : d.pairs) {
    md << "| " << p.pair << " | " << (p.beyond ? "yes" : "no") << " | " << p.chi2_sim << " | " << p.chi2_ext << " | "
       << p.error_sim << " | " << p.error_ext << " |\n";
  }
  if (plots) {
    md << "\n## Bode plots (measured with sigma, simulation, extended model; residuals measured/model)\n\n";
    for (const auto& p : d.pairs) md << "![" << p.pair << "](plots/" << pair_file_stem(p.pair) << ".png)\n\n";
  }
}

}  // namespace

std::string run_diagnose(const DiagnoseCommand& c) {
  if (c.out.empty()) throw InputError("--out DIR is required");
  if (c.engine.empty() == c.measured.empty()) throw InputError("give exactly one of --engine TRUTH.json or --measured DIR");
  Model sim = load_model_or_embedded(c.simulation);
  fs::create_directories(c.out);
  std::string data_dir = c.measured, data_name = c.measured;
  if (!c.engine.empty()) {
    MeasureOptions m = c.measure;
    m.engine = c.engine;
    if (m.inputs.empty()) {
      for (const auto& in : sim.inputs) m.inputs += (m.inputs.empty() ? "" : ",") + in.name;
    }
    m.out = c.out + "/measure";
    run_measure(m);
    // An independent measurement for validation, not used for fitting: another noise seed and a
    // second amplitude (1.5x), so amplitude-dependent effects (hysteresis, deadband) are verified.
    MeasureOptions v = m;
    v.seed = m.seed + 1;
    v.amplitude_scale = 1.5 * m.amplitude_scale;
    v.out = c.out + "/measure/validation";
    run_measure(v);
    data_dir = m.out;
    data_name = c.engine + " (measured by fralab, seed " + std::to_string(m.seed) + "; validation: seed " +
                std::to_string(v.seed) + " at 1.5x the amplitude)";
  }
  auto data = read_measured(data_dir);
  Diagnosis d = diagnose(sim, data);
  json_save_file(c.out + "/diagnosis.json", diagnosis_to_json(d));
  Model ext = d.extended;
  ext.name = sim.name + " + diagnosis";
  ext.warnings.clear();
  save_model(c.out + "/extended_model.json", ext);
  load_model(c.out + "/extended_model.json");  // it must be a valid fralab-model/1 the plant can run
  const bool plots = c.plots && render_plots(d, c.out);
  write_report(d, sim.name, data_name, plots, c.out);
  std::ostringstream s;
  s.precision(3);
  s << d.findings.size() << " findings; error " << d.error_before << " -> " << d.error_after;
  if (d.validation_before >= 0) s << " (validation " << d.validation_before << " -> " << d.validation_after << ")";
  for (const auto& f : d.findings) {
    s << "\n  " << f.cause << " [" << f.scope << (f.input.empty() ? "" : " " + f.input) << (f.output.empty() ? "" : " " + f.output) << "]";
    for (const auto& [k, v] : f.parameters) s << " " << k << "=" << v;
    for (const auto& [k, v] : f.text_parameters) s << " " << k << "=" << v;
  }
  s << "\n  report: " << c.out << "/report.md";
  return s.str();
}

}  // namespace fralab
