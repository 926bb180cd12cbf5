// `fralab diagnose`: measured data (a measure folder, or a fresh measurement of an engine model)
// against a simulation; writes DIR/diagnosis.json, DIR/extended_model.json and DIR/report.md with
// Bode plots (PNG, rendered by gnuplot).
#pragma once

#include <string>
#include <vector>

#include "fralab/core/measurement_chain.h"
#include "fralab/diagnose/diagnose.h"
#include "fralab/diagnose/report.h"
#include "fralab/lab/measure.h"

namespace fralab {

struct DiagnoseCommand {
  std::string simulation;
  std::string engine;  // measure this first (and once more, other seed, 1.5x amplitude: validation)
  std::string measured;  // or read this measure folder (its validation/ subfolder when present)
  /// A measure folder the simulation was fitted to or last agreed with: the measurement is
  /// diagnosed relative to it (diagnose/baseline.h); "" none.
  std::string baseline;
  /// Measure folders of the same pairs at further excitation levels (stage 7b refits each finding
  /// on each: its parameters per level and their law).
  std::vector<std::string> levels;
  /// The levels of `measured` and of each of `levels`, in that order, in the user's unit (a force
  /// rms in N, an amplitude); empty: each measurement's median excitation amplitude.
  std::vector<double> level_values;
  std::string out;
  MeasureOptions measure;  // flags of `measure`
  bool plots = true;
  /// With `engine`: the second measurement (another seed, 1.5x the amplitude) that checks the
  /// extended model on data it was not fitted to. Off (--no-validation), each finding earns its
  /// place on the fitting data alone (its removal must raise chi2 by more than k ln 2N and raise
  /// the error: diagnose.h), and the engine time halves.
  bool validation = true;
  /// With `engine`, measured by multisine (the auto campaign's or --excitation multisine) and no
  /// --zoom given: the simulation's light modes in the band (acquire/model_info.h: light_modes)
  /// get the multisine's zoom, lines enough inside each one's half-power band to size its
  /// frequency and damping (--no-zoom: the grid alone).
  bool zoom = true;
};

struct DiagnoseResult {
  std::string summary;  // one paragraph for the terminal
  /// With --engine: the measurements that ended partial (measure.h: partial_run_message), each
  /// one line. The diagnosis needs only their curves, so it runs all the same.
  std::vector<std::string> partial;
};

/// A measure folder's curves (its validation/ subfolder's as each pair's validation) and the
/// measurement chain they were recorded through: run.json's, else the tape's start event's, else
/// an ideal chain. InputError naming the tape when its start event's chain does not read.
struct MeasuredFolder {
  std::vector<MeasuredPair> data;
  MeasurementChain chain;
};
MeasuredFolder read_measured_folder(const std::string& dir);

/// Every run's "data_quality" (exchange/data_quality.h) under a measure folder: the folder's own
/// run.json (or the data_quality.json `fralab analyze` writes), an auto campaign's multisine/ and
/// sine/, and validation/ (each a section as run.json holds it, plus "folder"); the faults' lines
/// and whether any was checked added to `notes`. diagnosis.json's data_quality.runs. InputError
/// naming the file for a malformed section.
Json recorded_data_quality(const std::string& dir, DataNotes* notes);

/// Runs the diagnosis.
DiagnoseResult run_diagnose(const DiagnoseCommand& c);

}  // namespace fralab
