// The `fralab` driver's subcommands, one file each (lab/app/cmd_<name>.cc). Each adds itself to
// the CLI11 app with its flags and a callback that does the work; errors are thrown (InputError)
// and reported by main as one line on stderr with a non-zero exit status.
#pragma once

#include <CLI/CLI.hpp>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/lab/measure.h"

namespace fralab {

/// The flags every measuring subcommand shares (measure, run, diagnose --engine).
void add_measure_flags(CLI::App* c, MeasureOptions& m);
/// `--operating-point X` (or KEY=X): the model SETs named by --engine and --simulation, read at
/// that operating point (plant/schedule.h: a member, or interpolated between two).
void add_operating_point_flag(CLI::App* c, std::string& op);
/// `spec` at the operating point: "SPEC@OP" ("" or no op: spec unchanged).
std::string at_operating_point(const std::string& spec, const std::string& op);
/// "fralab: N pairs measured; engine time ..." on stdout.
void print_measure(const MeasureResult& r, const std::string& out);
/// After everything is written: PartialRun (exit status 3) naming each partial measurement.
void throw_if_partial(const std::vector<std::string>& partial);

void add_run_command(CLI::App& app);
void add_measure_command(CLI::App& app);
void add_analyze_command(CLI::App& app);
void add_fit_command(CLI::App& app);
void add_diagnose_command(CLI::App& app);
void add_tape_command(CLI::App& app);
void add_monitor_command(CLI::App& app);
void add_import_command(CLI::App& app);
void add_export_command(CLI::App& app);
void add_envelope_command(CLI::App& app);
void add_bound_command(CLI::App& app);

}  // namespace fralab
