#include "fralab/lab/measure.h"

#include <algorithm>
#include <filesystem>

#include "fralab/core/frd.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/pair_id.h"
#include "fralab/identify/fit_io.h"
#include "fralab/lab/auto_campaign.h"
#include "fralab/lab/run_lock.h"
#include "fralab/lab/run_record.h"
#include "fralab/lab/supervisor.h"
#include "measure_run.h"

namespace fralab {

namespace fs = std::filesystem;

std::vector<std::string> pairs_for_input(const std::string& x,
                                         const std::vector<std::string>& outs) {
  std::vector<std::string> p;
  for (const auto& o : outs) p.push_back(x + ":" + o);
  p.push_back(PairId::actuator_pair(x).str());
  for (const auto& o : outs) p.push_back(PairId{x, o, true}.str());
  return p;
}

void save_curves(std::vector<Frd>& curves, const std::string& dir) {
  std::sort(curves.begin(), curves.end(),
            [](const Frd& a, const Frd& b) { return a.pair < b.pair; });
  const MeasureDir md(dir);
  fs::create_directories(md.frd_dir());
  fs::create_directories(md.logs_dir());
  for (const Frd& f : curves) save_frd(md.frd(f.pair), f);
}

std::string save_curves_and_fit(std::vector<Frd>& curves, const std::string& dir,
                                const std::string& fit_delay, const std::string& title,
                                double timeout_s) {
  save_curves(curves, dir);
  const MeasureDir md(dir);
  FitOptions fo;
  parse_delay_option(fit_delay, &fo);  // a bad --delay is the caller's error, not a failed fit
  std::vector<std::string> args = {module_path("fralab-identify"),
                                   "--from-frd",
                                   dir,
                                   "--out",
                                   dir,
                                   "--delay",
                                   fit_delay,
                                   "--title",
                                   title};
  for (const Frd& f : curves) args.insert(args.end(), {"--pair", f.pair});
  Supervisor sup;
  sup.start({"identify", args, md.log("identify"), /*host=*/""});
  try {
    sup.wait_for({"identify"}, timeout_s);
  } catch (const Interrupted&) {
    throw;
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string partial_run_message(const MeasureResult& r, const std::string& dir) {
  return dir + ": partial run: everything was measured (tape and frd files complete), but " +
         r.failed_step + " failed: " + r.failure + "; fit again with `fralab measure --resume " +
         dir + "`";
}

void record_fit_outcome(RunOutcome& run, MeasureResult& r, const std::string& fit_failure) {
  run.reason.reset();
  if (fit_failure.empty()) {
    run.state = RunRecordState::kComplete;
    run.failed_step.reset();
    r.failed_step.clear(), r.failure.clear();
    return;
  }
  run.state = RunRecordState::kPartial;
  run.failed_step = FailedStep{"identify", fit_failure};
  r.failed_step = "identify";
  r.failure = fit_failure;
}

MeasureResult run_measure(const MeasureOptions& given) {
  MeasureRun::check_can_start(given);
  // The folder is this run's until it ends: a second run or a resume on it is refused.
  const RunLock lock(given.out, given.resume ? "fralab measure --resume" : "fralab measure");
  MeasureRun run(given);
  run.prepare_supervision();
  try {
    run.start_and_supervise();
    run.wait_for_identifier();
    run.verify_tape();
    run.check_data();
    run.analyse_resumed();
  } catch (const std::exception& e) {
    throw run.abandon(e);
  }
  return run.finish();
}

MeasureResult measure(const MeasureOptions& o) {
  if (o.out.empty()) throw InputError("--out DIR is required");
  if (o.auto_campaign) return run_auto_campaign(o).measure;
  if (const MeasureDir dir(o.out);
      o.resume && fs::exists(dir.run_json()) &&
      std::holds_alternative<AutoRunRecord>(load_any_run_record(dir.run_json())))
    return resume_auto_campaign(o.out);
  return run_measure(o);
}

}  // namespace fralab
