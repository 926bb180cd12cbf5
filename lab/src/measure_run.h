// One plain `fralab measure` run (the auto campaign is a sequence of these: lab/auto_campaign.h),
// as the named steps run_measure drives in order: prepare, supervise, verify, finish. Each step
// reads and extends the run's state kept here.
#pragma once

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"
#include "fralab/core/measure_dir.h"
#include "fralab/lab/deputy.h"
#include "fralab/lab/measure.h"
#include "fralab/lab/process_plan.h"
#include "fralab/lab/resume.h"
#include "fralab/lab/run_record.h"
#include "fralab/lab/supervisor.h"
#include "fralab/plant/model.h"

namespace fralab {

class MeasureRun {
 public:
  /// Refuses, before the folder is locked or anything written, a run that cannot start: no --out,
  /// --resume DIR without DIR/run.json, or an auto campaign (measure() runs and resumes those).
  static void check_can_start(const MeasureOptions& given);

  /// Prepares the run (the caller holds DIR's lock): the options (on --resume, those recorded in
  /// DIR/run.json), the model (saved as DIR/engine.json on a fresh run), the run id and LCM URL,
  /// on --resume the resume point (the tape cut at its last whole event); DIR/run.json then says
  /// "running" with everything needed to resume.
  explicit MeasureRun(const MeasureOptions& given);

  /// Stop signals are caught from now on (the processes are stopped in order), and the deputies
  /// of a multi-host run answer before anything starts.
  void prepare_supervision();
  /// Starts the plan's processes (plan_processes), the acquisition last, and waits until the
  /// measurement is over: plant, analysers and acquisition exited. Nothing when a resumed run's
  /// tape is already complete.
  void start_and_supervise();
  /// A fresh run's identifier: its failure leaves the measurement whole (the run ends partial).
  void wait_for_identifier();
  /// The tape read back (every tape block and status event, the done status) while the recorder
  /// still runs, then the recorder stopped; InputError naming the tape when something is missing.
  void verify_tape();
  /// The tape's data checked (exchange/data_quality.h; DIR/run.json "data_quality"), each fault
  /// printed; when one was mended, every pair analysed again from the mended series (the tape
  /// stays as recorded).
  void check_data();
  /// A resumed run has no live analysers: the whole tape is analysed as they would (tape = live),
  /// then fitted as the live identifier would. A run whose data were mended: its curves of the
  /// mended series saved over the live ones and fitted again.
  void analyse_resumed();
  /// On a failure or a stop signal: every process stopped (the acquisition first), DIR/run.json
  /// "interrupted" or "failed" with the reason; returns the error to throw, which says how to
  /// resume.
  InputError abandon(const std::exception& e);
  /// The run's record completed: engine time (the adaptive campaign's as it grew), the
  /// acquisition's retransmissions, the adaptive steps, the fit's outcome; DIR/run.json
  /// "complete" or "partial".
  MeasureResult finish();

 private:
  // The preparation, in order.
  // The options (on --resume from DIR/run.json), the model, the selected inputs and their pairs;
  // the folder made and, on a fresh run, the model saved as DIR/engine.json.
  void read_options(const MeasureOptions& given);
  // A private LCM URL (ttl=1 for a multi-host run) and a fresh run id (a resumed run keeps its
  // own), so that runs sharing a machine do not mix.
  void choose_run_id_and_url();
  // On --resume: the tape cut at its last whole event and where the run starts again.
  void find_resume_point();
  // On a fresh run: the tape removed and DIR/run.json started with what a resume needs.
  void start_record();

  MeasureOptions o_;  // as run; o_.acquire as the acquisition runs it (inputs by name, decisions)
  Model model_;
  MeasureDir dir_;
  RunRecord run_;  // DIR/run.json
  std::string url_;
  ResumePoint from_;  // a fresh run starts at the default
  MeasureResult r_;
  std::optional<std::vector<Frd>> mended_curves_;  // check_data(): the mended series' curves
  std::string fit_failure_;  // the identifier's, when it failed after everything was measured
  std::chrono::steady_clock::time_point t_fit_;
  // Deputies for the processes on other hosts (declared before the supervisor: it uses them until
  // its end).
  std::unique_ptr<lcm::LCM> deputy_lcm_;
  std::unique_ptr<DeputyClient> deputies_;
  Supervisor sup_;
};

}  // namespace fralab
