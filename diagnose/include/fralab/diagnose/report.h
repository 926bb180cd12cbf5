// The diagnosis's files: the measured pairs read from a `measure` folder, the report
// (DIR/report.md, with one gnuplot Bode plot per pair in DIR/plots/) and the terminal summary.
#pragma once

#include <string>
#include <vector>

#include "fralab/diagnose/data_faults.h"
#include "fralab/diagnose/diagnose.h"

namespace fralab {

/// Every DIR/frd/*.json as a MeasuredPair (sorted by pair), with DIR/validation/frd/<same>.json as
/// its validation when present. InputError when DIR has no frd/ or no frd files.
std::vector<MeasuredPair> read_measured_dir(const std::string& dir);

/// One PNG and one SVG per pair in DIR/plots: measured (with sigma bars), simulation, extended
/// model, and the residuals; and the overview of the transfer matrix (plots/overview.png, .svg:
/// every pair whose E1 is not an actuator command u_X, outputs by inputs, render_bode_overview).
/// false when gnuplot is missing or failed (the report then has no figures).
bool render_diagnosis_plots(const Diagnosis& d, const std::string& dir);

/// What the report says of the data (docs/method/data-quality.md): one line per fault the
/// recordings' checks found (with its run folder), and the findings' data alternatives.
struct DataNotes {
  bool checked = false;             // the recordings were checked (else the section says so)
  std::vector<std::string> faults;  // one line each
  std::vector<DataAlternative> alternatives;
};

/// DIR/report.md: errors, what to look at in the data before trusting a finding, findings with
/// their explanation (and their data alternatives), the per-pair table, the figures.
void write_diagnosis_report(const Diagnosis& d, const std::string& sim_name,
                            const std::string& data_name, bool plots, const std::string& dir,
                            const DataNotes& data = {});

/// DIR/report.html beside DIR/report.md (written first): the same report rendered from its
/// markdown by cmark-gfm, one self-contained file: each figure's SVG (plots/STEM.svg) inline in
/// place of its PNG. InputError when report.md is missing or the page cannot be written.
void write_report_html(const std::string& dir, const std::string& title);

/// The findings as printed on the terminal: a count and errors, one line per finding.
std::string diagnosis_summary(const Diagnosis& d, const std::string& dir);

}  // namespace fralab
