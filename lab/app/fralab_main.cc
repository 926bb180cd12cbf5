// fralab: the one driver. Subcommands spawn the module executables as separate processes talking
// LCM (run, measure) or run a module's library directly on files (analyze --log, fit, tape). Exit
// status 0 on success; 3 for a partial run (everything measured, a later step such as the fit
// failed: lab/measure.h); otherwise 1 (CLI11's code, above 100, for a bad command line) with a
// one-line reason on stderr.
#include <cstdio>
#include <exception>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"fralab: frequency-response identification lab (J85-13 by default)"};
  app.require_subcommand(1);
  fralab::add_run_command(app);
  fralab::add_measure_command(app);
  fralab::add_analyze_command(app);
  fralab::add_fit_command(app);
  fralab::add_diagnose_command(app);
  fralab::add_tape_command(app);
  fralab::add_monitor_command(app);
  fralab::add_import_command(app);
  fralab::add_export_command(app);
  fralab::add_envelope_command(app);
  fralab::add_bound_command(app);
  try {
    app.parse(argc, argv);  // the chosen subcommand's callback runs here
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const fralab::PartialRun& e) {  // measured whole, a later step failed
    std::fprintf(stderr, "fralab: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fralab: %s\n", e.what());
    return 1;
  }
  return 0;
}
