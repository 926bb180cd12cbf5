// The lab launcher behind `fralab run` and `fralab measure`: starts the recorder, the plant, one
// analyser per channel pair and the acquisition as separate processes on a private LCM URL,
// supervises them, verifies the tape holds every block, and stops them cleanly. DIR/run.json
// records the run from its start ("state": running, complete, failed with "reason", interrupted);
// a signal (SIGINT, SIGTERM, SIGHUP) stops the acquisition first (the actuators commanded back to
// their operating point), then every other process; a failed or interrupted run keeps its tape
// and continues with `--resume DIR` (lab/resume.h).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "fralab/acquire/acquisition.h"
#include "fralab/core/frd.h"
#include "fralab/core/json_util.h"
#include "fralab/core/measurement_chain.h"
#include "fralab/exchange/data_quality.h"
#include "fralab/lab/run_record.h"
#include "fralab/plant/model.h"

namespace fralab {

/// How the live analysers share a run's pairs. Each pair has its own two-channel analyser; an
/// instance (a process) decodes a tape block once for all its pairs; the instances run in
/// parallel. The curves do not depend on the grouping. By default one instance per input: on two
/// cores the J85's stepped lab runs at 254x instead of 88x, the load about 2 instead of 28
/// (docs/validation.md §1).
struct AnalyserGrouping {
  enum class By {
    kPair,   // "pair": each position-relative pair (X:O, u_X:X) alone, an input's
             // command-relative pairs (u_X:O, one reference) together
    kInput,  // "input": one instance per input, all its pairs
    kCount,  // N: N pairs an instance, input by input
  };
  By by = By::kInput;
  int pairs = 0;  // kCount: pairs an instance, >= 1
  /// "pair", "input" or a whole number >= 1; InputError naming the word otherwise.
  static AnalyserGrouping parse(const std::string& word);
  std::string str() const;
};

struct MeasureOptions {
  std::string engine = "j85_95";
  AcquireOptions acquire;  // the excitation (passed to fralab-acquire losslessly)
  uint64_t seed = 1;       // plant noise seed
  std::string out;
  bool no_noise = false;
  double plant_jitter_ms = 0;  // a free-running plant's tick times off by up to this (uniform)
  std::string lcm_url;         // "" = a fresh private URL
  double timeout_s = 3600;
  std::string fit_delay = "auto";  // the identifier's --delay
  /// Fit the curves (the live identifier; DIR/tf, DIR/transfer_matrix.*). false: the curves
  /// only, for a caller that fits them itself (the auto campaign fits its merged curves once).
  bool fit = true;
  AnalyserGrouping analysers;   // --analysers
  double stall_timeout_s = 60;  // a stream standing still this long fails the run (acquire)
  /// Continue the run in `out` (its run.json holds every other option) from its first incomplete
  /// step (lab/resume.h).
  bool resume = false;
  /// Multi-host (explicit opt-in, needs FRALAB_NETWORK=1): process kind ("plant", "recorder",
  /// "acquire", "analyze" for every analyser, "identify") -> the deputy that runs it on its host
  /// (lab/deputy.h); the run's URL then has ttl=1. Paths (model, tape, DIR) must be the same on
  /// every host (a shared folder).
  std::map<std::string, std::string> hosts;
  std::string deputy_url;  // "" = kDefaultDeputyUrl
  bool progress = true;    // the progress line on stderr when it is a terminal (lab/progress.h)
  /// `--excitation auto`: the campaign that decides itself (lab/auto_campaign.h), an orthogonal
  /// multisine and a sine for the inputs that distort at its level. measure() runs it;
  /// run_measure, which runs one plain measurement, refuses it.
  bool auto_campaign = false;
  /// The campaign's earlier runs' clock estimates (each labelled with its run's folder): the data
  /// checks pool each channel's with this run's own (exchange/data_quality.h).
  std::vector<ClockEstimate> clock_estimates;
};

struct MeasureResult {
  std::vector<std::string> pairs;
  double engine_time_s = 0;
  double wall_time_s = 0;  // acquisition and analysis (plant, acquire, analysers, recorder)
  double fit_time_s = 0;   // the identifier, after the analysers finished
  int64_t tape_blocks = 0;
  std::string run_id;
  /// A partial run: everything was measured (the tape and every frd file are complete) but a
  /// step after measuring failed: the step ("identify": the fits, transfer matrix or state
  /// model) and its error. DIR/run.json says the same ("state": "partial", "failed_step").
  std::string failed_step, failure;
  bool partial() const { return !failed_step.empty(); }
  /// MeasureOptions::clock_estimates and this measurement's runs' own, labelled with their
  /// folders (none where the checks did not run): what a later run of the campaign pools with.
  std::vector<ClockEstimate> clock_estimates;
};

/// Thrown by the commands after a partial run has written everything it could (exit status 3):
/// the measurement is whole, a later step failed.
struct PartialRun : InputError {
  using InputError::InputError;
};

/// The one-line account of a partial run in DIR: "DIR: partial run: everything was measured (tape
/// and frd files complete), but identify failed: <error>; fit again with `fralab measure --resume
/// DIR`".
std::string partial_run_message(const MeasureResult& r, const std::string& dir);

/// The pairs measured for an input X of a model with outputs O: X:O for every output, u_X:X, and
/// u_X:O for every output.
std::vector<std::string> pairs_for_input(const std::string& input,
                                         const std::vector<std::string>& outputs);

/// One plain run into opt.out (or its continuation, opt.resume): the recorder, plant, analysers,
/// identifier and acquisition started as plan_processes says (lab/process_plan.h) and supervised,
/// the tape verified, DIR/run.json completed. InputError for an auto campaign, which measure()
/// runs.
MeasureResult run_measure(const MeasureOptions& opt);

/// What `fralab measure`, `fralab run` and `fralab diagnose --engine` run: the auto campaign when
/// opt.auto_campaign (run_auto_campaign, whose runs are plain ones), the refit of a partial auto
/// campaign on --resume of its folder (resume_auto_campaign), else run_measure.
MeasureResult measure(const MeasureOptions& opt);

/// The curves in pair order (sorted in place), each to DIR/frd/<stem>.json (DIR/logs made too).
void save_curves(std::vector<Frd>& curves, const std::string& dir);

/// A measurement's results from its curves, as the live analysers and identifier leave them:
/// the curves in pair order (sorted in place), each to DIR/frd/<stem>.json, then fitted
/// (`fit_delay`: the identifier's --delay) into DIR/tf and DIR/transfer_matrix.{json,md} under
/// `title` by `fralab-identify --from-frd DIR` in a process of its own (its log
/// DIR/logs/identify.log), so that a crash in fitting leaves the curves whole. Returns "" when the
/// fit succeeded, else its failure ("identify was killed by signal 11"); Interrupted on a stop
/// signal (Supervisor::catch_stop_signals).
std::string save_curves_and_fit(std::vector<Frd>& curves, const std::string& dir,
                                const std::string& fit_delay, const std::string& title,
                                double timeout_s = 3600);

/// DIR/run.json's state after a run's fit (either record, lab/run_record.h): "complete", or
/// "partial" with failed_step {"identify", error} (the same in `r`) when `fit_failure` is not "";
/// no reason either way.
void record_fit_outcome(RunOutcome& run, MeasureResult& r, const std::string& fit_failure);

}  // namespace fralab
