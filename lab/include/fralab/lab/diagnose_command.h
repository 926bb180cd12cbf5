// `fralab diagnose`: measured data (a measure folder, or a fresh measurement of an engine model)
// against a simulation; writes DIR/diagnosis.json, DIR/extended_model.json and DIR/report.md with
// Bode plots (PNG, rendered by gnuplot).
#pragma once

#include <string>

#include "fralab/lab/measure.h"

namespace fralab {

struct DiagnoseCommand {
  std::string simulation;
  std::string engine;  // measure this first (and once more, other seed, 1.5x amplitude: validation)
  std::string measured;  // or read this measure folder (its validation/ subfolder when present)
  std::string out;
  MeasureOptions measure;  // flags of `measure`
  bool plots = true;
};

/// Runs the diagnosis; returns a one-paragraph summary for the terminal.
std::string run_diagnose(const DiagnoseCommand& c);

}  // namespace fralab
