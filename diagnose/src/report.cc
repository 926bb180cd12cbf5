#include "fralab/diagnose/report.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "fralab/analyze/bode_plot.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/pair_id.h"

namespace fralab {

namespace fs = std::filesystem;

std::vector<MeasuredPair> read_measured_dir(const std::string& dir) {
  const MeasureDir md(dir);
  if (!fs::exists(md.frd_dir())) throw InputError(dir + ": not a measure folder (no frd/ inside)");
  std::vector<MeasuredPair> v;
  for (const auto& e : fs::directory_iterator(md.frd_dir())) {
    if (e.path().extension() != ".json") continue;
    MeasuredPair m;
    m.frd = load_frd(e.path().string());
    m.pair = m.frd.pair;
    const std::string val = md.validation().frd_dir() + "/" + e.path().filename().string();
    if (fs::exists(val)) m.validation = load_frd(val);
    v.push_back(m);
  }
  std::sort(v.begin(), v.end(),
            [](const MeasuredPair& a, const MeasuredPair& b) { return a.pair < b.pair; });
  if (v.empty()) throw InputError(dir + "/frd: no frd files");
  return v;
}

// One PNG per pair: measured (with sigma bars), simulation, extended model, and the residuals.
bool render_diagnosis_plots(const Diagnosis& d, const std::string& dir) {
  std::vector<BodePlot> plots;
  for (const auto& p : d.pairs) {
    const PairId id = PairId::parse(p.pair);
    plots.push_back({p.pair + " (response " + id.output + "/" + id.e1() + ")",
                     pair_file_stem(p.pair),
                     p.w,
                     p.meas,
                     p.sigma,
                     {{"simulation", p.sim}, {"extended model", p.ext}}});
  }
  const std::string pdir = dir + "/plots";
  if (!render_bode_plots(plots, pdir) ||
      !render_bode_plots(plots, pdir, "plots_svg.gp", PlotFormat::kSvg))
    return false;
  // The overview: outputs (rows) by inputs (columns), in order of first appearance.
  std::vector<std::string> rows, cols;
  auto add = [](std::vector<std::string>& v, const std::string& s) {
    if (std::find(v.begin(), v.end(), s) == v.end()) v.push_back(s);
  };
  for (const auto& p : d.pairs) {
    const PairId id = PairId::parse(p.pair);
    if (id.command) continue;
    add(cols, id.input);
    add(rows, id.output);
  }
  if (rows.empty()) return true;
  std::vector<std::vector<const BodePlot*>> grid(rows.size(),
                                                 std::vector<const BodePlot*>(cols.size()));
  for (size_t i = 0; i < d.pairs.size(); ++i) {
    const PairId id = PairId::parse(d.pairs[i].pair);
    const auto r = std::find(rows.begin(), rows.end(), id.output),
               c = std::find(cols.begin(), cols.end(), id.e1());
    if (r != rows.end() && c != cols.end())
      grid[size_t(r - rows.begin())][size_t(c - cols.begin())] = &plots[i];
  }
  const std::string title = "measured (points), simulation (red), extended model (blue, dashed)";
  // The overview is a bonus: the report references it only when it was drawn.
  if (!render_bode_overview(grid, rows, cols, title, pdir, "overview", PlotFormat::kPng) ||
      !render_bode_overview(grid, rows, cols, title, pdir, "overview", PlotFormat::kSvg))
    std::filesystem::remove(pdir + "/overview.png");
  return true;
}

namespace {

// The report's sections, each written to md in order (md's precision, set by the first, holds).
void report_header(std::ostream& md, const Diagnosis& d, const std::string& sim_name,
                   const std::string& data_name) {
  md << "# Diagnosis: " << sim_name << "\n\nMeasured data: " << data_name << "\n\n";
  md << "Error (" << d.metric << "): simulation **" << std::setprecision(3) << d.error_before
     << "**, extended model **" << d.error_after << "**";
  if (d.validation_before >= 0) {
    md << "; on the independent validation measurement: " << d.validation_before << " -> "
       << d.validation_after;
  }
  md << ".\n\nMeasurement chain (the simulation is compared as the lab measured it): ";
  if (d.chain.sample_rate_hz > 0) {
    md << (d.chain.hold == MeasurementChain::Hold::kFirstOrder ? "first-order" : "zero-order")
       << " hold at " << d.chain.sample_rate_hz << " Hz, converter delay "
       << d.chain.converter_delay_s << " s";
    for (size_t i = 0; i < d.chain.reheld_inputs.size(); ++i)
      md << (i ? ", " : "; paths held again from the position of ") << d.chain.reheld_inputs[i];
  } else {
    md << "ideal (none recorded)";
  }
  md << ".\n";
}

void report_data_quality(std::ostream& md, const DataNotes& data) {
  md << "\n## Data quality\n\n";
  if (!data.checked) {
    md << "The recordings were not checked (measured before fralab checked them): look at "
          "them before trusting a finding.\n";
  } else if (data.faults.empty()) {
    md << "Every recorded channel checked (clipping, held and lost samples, mains hum, drift, "
          "clock, response): nothing found.\n";
  }
  for (const std::string& l : data.faults) md << "- " << l << "\n";
  for (const DataAlternative& a : data.alternatives)
    if (a.finding < 0) md << "- " << a.text << ".\n";
}

void report_findings(std::ostream& md, const Diagnosis& d, const DataNotes& data) {
  md << "\n## Findings\n\n";
  if (d.findings.empty())
    md << "None: every measured response agrees with the simulation within its uncertainty.\n";
  for (const auto& f : d.findings) {
    md << "- **" << to_string(f.cause) << "** (" << to_string(f.scope);
    if (!f.input.empty()) md << ", input " << f.input;
    if (!f.output.empty()) md << ", output " << f.output;
    md << "):";
    for (const auto& [k, v] : f.parameters) md << " " << to_string(k) << " = " << v;
    for (const auto& [k, v] : f.text_parameters) md << " " << k << " = " << v;
    for (const auto& [k, v] : f.intervals)
      md << " (" << to_string(k) << " 1-sigma " << v[0] << " .. " << v[1] << ")";
    md << ". " << f.explanation << ". Error " << f.error_before << " -> " << f.error_after
       << " over ";
    for (size_t i = 0; i < f.pairs.size(); ++i) md << (i ? ", " : "") << f.pairs[i];
    md << ".\n";
    for (const DataAlternative& a : data.alternatives)
      if (a.finding == int(&f - d.findings.data()))
        md << "  - Data alternative: " << a.text << ".\n";
  }
}

// What fits as well (the state model's other sets), what was dropped, and what nothing explains.
void report_beside_findings(std::ostream& md, const Diagnosis& d) {
  if (!d.state_alternatives.empty()) {
    md << "\n## As well fitted (other entries of the state model the data cannot tell apart)\n\n";
    for (const StateAlternative& a : d.state_alternatives) {
      md << "-";
      for (const Finding& f : a.findings) {
        md << " **" << to_string(f.cause) << "**";
        for (const auto& [k, v] : f.text_parameters) md << " " << k << " = " << v;
        for (const auto& [k, v] : f.parameters) md << " " << to_string(k) << " = " << v;
        md << ";";
      }
      md << " chi2 above the named set's by " << a.chi2_above
         << " (misfit units): check which the plant holds.\n";
    }
  }
  if (!d.dropped.empty()) {
    md << "\n## Dropped (fitted, but did not earn their place)\n\n";
    for (const auto& x : d.dropped) {
      md << "- " << to_string(x.finding.cause) << " (" << to_string(x.finding.scope);
      if (!x.finding.input.empty()) md << ", input " << x.finding.input;
      if (!x.finding.output.empty()) md << ", output " << x.finding.output;
      md << "):";
      for (const auto& [k, v] : x.finding.parameters) md << " " << to_string(k) << " = " << v;
      md << ": " << x.reason << ".\n";
    }
  }
  if (!d.unexplained.empty()) {
    md << "\n## Unexplained (beyond the uncertainty, no cause of the catalogue fits)\n\n";
    for (const auto& u : d.unexplained) {
      md << "- " << u.pair << ": " << u.band_hz[0] << "-" << u.band_hz[1]
         << " Hz, largest |ln(measured/model)| " << u.residual << ", chi2 " << u.chi2 << ": "
         << u.explanation << ".\n";
    }
  }
}

void report_pairs(std::ostream& md, const Diagnosis& d, bool plots, const std::string& dir) {
  md << "\n## Pairs\n\n| pair | beyond uncertainty | chi2 sim | chi2 extended | error sim | error "
        "extended |\n|---|---|---|---|---|---|\n";
  for (const auto& p : d.pairs) {
    md << "| " << p.pair << " | " << (p.beyond ? "yes" : "no") << " | " << p.chi2_sim << " | "
       << p.chi2_ext << " | " << p.error_sim << " | " << p.error_ext << " |\n";
  }
  if (!plots) return;
  if (std::filesystem::exists(dir + "/plots/overview.png"))
    md << "\n## The transfer matrix at a glance\n\nGain (dB) above phase (degrees) of each "
          "output (rows) per input (columns) over frequency (Hz).\n\n"
       << "![the transfer matrix: measured, simulation, extended model](plots/overview.png)\n";
  md << "\n## Bode plots (measured with sigma, simulation, extended model; residuals "
        "measured/model)\n\n";
  for (const auto& p : d.pairs)
    md << "![" << p.pair << "](plots/" << pair_file_stem(p.pair) << ".png)\n\n";
}

}  // namespace

void write_diagnosis_report(const Diagnosis& d, const std::string& sim_name,
                            const std::string& data_name, bool plots, const std::string& dir,
                            const DataNotes& data) {
  std::ofstream md(dir + "/report.md");
  report_header(md, d, sim_name, data_name);
  report_data_quality(md, data);
  report_findings(md, d, data);
  report_beside_findings(md, d);
  report_pairs(md, d, plots, dir);
}

std::string diagnosis_summary(const Diagnosis& d, const std::string& dir) {
  std::ostringstream s;
  s.precision(3);
  s << d.findings.size() << " findings; error " << d.error_before << " -> " << d.error_after;
  if (d.validation_before >= 0)
    s << " (validation " << d.validation_before << " -> " << d.validation_after << ")";
  for (const auto& f : d.findings) {
    s << "\n  " << finding_label(f);
    for (const auto& [k, v] : f.parameters) s << " " << to_string(k) << "=" << v;
    for (const auto& [k, v] : f.text_parameters) s << " " << k << "=" << v;
  }
  s << "\n  report: " << dir << "/report.md, " << dir << "/report.html";
  return s.str();
}

}  // namespace fralab
