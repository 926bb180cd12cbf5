#include "diagnose_cmd.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "fralab/analyze/bode_plot.h"
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
  std::sort(v.begin(), v.end(),
            [](const MeasuredPair& a, const MeasuredPair& b) { return a.pair < b.pair; });
  if (v.empty()) throw InputError(dir + "/frd: no frd files");
  return v;
}

// One PNG per pair: measured (with sigma bars), simulation, extended model, and the residuals.
bool render_plots(const Diagnosis& d, const std::string& dir) {
  std::vector<BodePlot> plots;
  for (const auto& p : d.pairs) {
    const auto [x, y] = split_pair(p.pair);
    plots.push_back({p.pair + " (response " + y + "/" + x + ")",
                     pair_file_stem(p.pair),
                     p.w,
                     p.meas,
                     p.sigma,
                     {{"simulation", p.sim}, {"extended model", p.ext}}});
  }
  return render_bode_plots(plots, dir + "/plots");
}

void write_report(const Diagnosis& d, const std::string& sim_name, const std::string& data_name,
                  bool plots, const std::string& dir) {
  std::ofstream md(dir + "/report.md");
  md << "# Diagnosis: " << sim_name << "\n\nMeasured data: " << data_name << "\n\n";
  md << "Error (" << d.metric << "): simulation **" << std::setprecision(3) << d.error_before
     << "**, extended model **" << d.error_after << "**";
  if (d.validation_before >= 0) {
    md << "; on the independent validation measurement: " << d.validation_before << " -> "
       << d.validation_after;
  }
  md << ".\n\n## Findings\n\n";
  if (d.findings.empty())
    md << "None: every measured response agrees with the simulation within its uncertainty.\n";
  for (const auto& f : d.findings) {
    md << "- **" << f.cause << "** (" << f.scope;
    if (!f.input.empty()) md << ", input " << f.input;
    if (!f.output.empty()) md << ", output " << f.output;
    md << "):";
    for (const auto& [k, v] : f.parameters) md << " " << k << " = " << v;
    for (const auto& [k, v] : f.text_parameters) md << " " << k << " = " << v;
    md << ". " << f.explanation << ". Error " << f.error_before << " -> " << f.error_after
       << " over ";
    for (size_t i = 0; i < f.pairs.size(); ++i) md << (i ? ", " : "") << f.pairs[i];
    md << ".\n";
  }
  md << "\n## Pairs\n\n| pair | beyond uncertainty | chi2 sim | chi2 extended | error sim | error "
        "extended |\n|---|---|---|---|---|---|\n";
  for (const auto& p : d.pairs) {
    md << "| " << p.pair << " | " << (p.beyond ? "yes" : "no") << " | " << p.chi2_sim << " | "
       << p.chi2_ext << " | " << p.error_sim << " | " << p.error_ext << " |\n";
  }
  if (plots) {
    md << "\n## Bode plots (measured with sigma, simulation, extended model; residuals "
          "measured/model)\n\n";
    for (const auto& p : d.pairs)
      md << "![" << p.pair << "](plots/" << pair_file_stem(p.pair) << ".png)\n\n";
  }
}

}  // namespace

std::string run_diagnose(const DiagnoseCommand& c) {
  if (c.out.empty()) throw InputError("--out DIR is required");
  if (c.engine.empty() == c.measured.empty())
    throw InputError("give exactly one of --engine TRUTH.json or --measured DIR");
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
    data_name = c.engine + " (measured by fralab, seed " + std::to_string(m.seed) +
                "; validation: seed " + std::to_string(v.seed) + " at 1.5x the amplitude)";
  }
  auto data = read_measured(data_dir);
  Diagnosis d = diagnose(sim, data);
  json_save_file(c.out + "/diagnosis.json", diagnosis_to_json(d));
  Model ext = d.extended;
  ext.name = sim.name + " + diagnosis";
  ext.warnings.clear();
  save_model(c.out + "/extended_model.json", ext);
  load_model(c.out +
             "/extended_model.json");  // it must be a valid fralab-model/1 the plant can run
  const bool plots = c.plots && render_plots(d, c.out);
  write_report(d, sim.name, data_name, plots, c.out);
  std::ostringstream s;
  s.precision(3);
  s << d.findings.size() << " findings; error " << d.error_before << " -> " << d.error_after;
  if (d.validation_before >= 0)
    s << " (validation " << d.validation_before << " -> " << d.validation_after << ")";
  for (const auto& f : d.findings) {
    s << "\n  " << f.cause << " [" << f.scope << (f.input.empty() ? "" : " " + f.input)
      << (f.output.empty() ? "" : " " + f.output) << "]";
    for (const auto& [k, v] : f.parameters) s << " " << k << "=" << v;
    for (const auto& [k, v] : f.text_parameters) s << " " << k << "=" << v;
  }
  s << "\n  report: " << c.out << "/report.md";
  return s.str();
}

}  // namespace fralab
