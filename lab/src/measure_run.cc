#include "measure_run.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <filesystem>
#include <iostream>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/acquire/acquisition_summary.h"
#include "fralab/acquire/model_info.h"
#include "fralab/envelope/envelope.h"
#include "fralab/lab/data_check.h"
#include "fralab/lab/progress.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/lab_lcm.h"
#include "fralab/lcm/url.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/simulator.h"
#include "tape_analysis.h"
#include "tape_check.h"

namespace fralab {

namespace fs = std::filesystem;

namespace {

// The run's record, DIR/run.json: written when the run starts (state "running", with what is
// needed to resume it), and again when it ends ("complete", "failed" with the reason,
// "interrupted").
void save_run(const std::string& out, const RunRecord& run) {
  save_run_record(MeasureDir(out).run_json(), run);
}

// The options of the run recorded in DIR/run.json (--resume DIR).
MeasureOptions options_from_run(const std::string& dir, const RunRecord& run) {
  MeasureOptions o;
  o.out = dir;
  o.resume = true;
  const RunOptions& opt = run.options;
  o.engine = MeasureDir(dir).engine();
  o.seed = opt.seed;
  o.no_noise = opt.no_noise;
  o.fit_delay = opt.fit_delay;
  o.fit = opt.fit.value_or(true);
  o.timeout_s = opt.timeout_s.value_or(o.timeout_s);
  o.stall_timeout_s = opt.stall_timeout_s.value_or(o.stall_timeout_s);
  o.hosts = opt.hosts.value_or(o.hosts);
  o.deputy_url = opt.deputy_url.value_or(o.deputy_url);
  try {
    std::vector<std::string> flags = opt.acquire_flags;
    CLI::App app;
    add_acquire_flags(&app, o.acquire);
    std::reverse(flags.begin(), flags.end());  // CLI11 parses a vector from its back
    app.parse(flags);
  } catch (const std::exception& e) {
    throw InputError(dir + "/run.json: cannot resume from it: " + e.what());
  }
  return o;
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The progress line, on a terminal only: it listens to the run's status events and
// retransmission requests on the run's URL, and is redrawn on the supervisor's polls (at most
// every 0.2 s).
class ProgressWatch {
 public:
  ProgressWatch(const std::string& url, const std::string& run_id, bool wanted,
                std::chrono::steady_clock::time_point t0)
      : listener_{&progress_, run_id}, t0_(t0), last_draw_(t0) {
    if (!isatty(STDERR_FILENO) || !wanted) return;
    watch_ = std::make_unique<lcm::LCM>(url);
    if (watch_->good()) {
      watch_->subscribe(kStatusChannel, &Listener::on_status, &listener_);
      watch_->subscribe(kFlowChannel, &Listener::on_flow, &listener_);
    } else {
      watch_.reset();
    }
  }
  ProgressWatch(const ProgressWatch&) = delete;

  void draw() {
    if (!watch_) return;
    try {
      while (watch_->handleTimeout(0) > 0) {
      }
    } catch (const InputError&) {  // a malformed status: the line is only a face
    }
    if (seconds_since(last_draw_) < 0.2) return;
    last_draw_ = std::chrono::steady_clock::now();
    const std::string l = progress_.line(seconds_since(t0_));
    if (l != shown_ && !l.empty()) std::cerr << "\r" << l << "\033[K" << std::flush;
    shown_ = l;
  }
  // The line's last state, ended with a newline.
  void finish() {
    if (!shown_.empty()) std::cerr << "\r" << progress_.line(seconds_since(t0_)) << "\033[K\n";
  }
  // The line ended, so the error that follows starts a line of its own.
  void abandon() {
    if (!shown_.empty()) std::cerr << "\n";
  }

 private:
  struct Listener {
    ProgressLine* p;
    std::string run_id;
    void on_status(const lcm::ReceiveBuffer* rb, const std::string& ch) {
      const StatusEvent e = decode_status_event(rb, ch);
      if (e.run_id == run_id) p->on_status(e);
    }
    void on_flow(const lcm::ReceiveBuffer* rb, const std::string& ch) {
      const auto f = decode_checked<flow_t>(rb, ch);
      if (f.run_id == run_id && f.kind == "resend") p->on_resent(f.to_seq - f.from_seq + 1);
    }
  };
  ProgressLine progress_;
  Listener listener_;
  std::unique_ptr<lcm::LCM> watch_;
  std::string shown_;
  std::chrono::steady_clock::time_point t0_, last_draw_;
};

}  // namespace

void MeasureRun::check_can_start(const MeasureOptions& given) {
  if (given.out.empty()) throw InputError("--out DIR is required");
  if (given.auto_campaign)
    throw InputError("run_measure: an auto campaign is run by measure() (lab/auto_campaign.h)");
  const MeasureDir dir(given.out);
  if (given.resume && !fs::exists(dir.run_json())) {
    if (fs::exists(dir.multisine().run_json()))
      throw InputError(given.out +
                       ": an auto campaign that did not end resumes its runs one by one: "
                       "`fralab measure --resume " +
                       given.out + "/multisine` (or /sine)");
    throw InputError(given.out +
                     "/run.json: no such file: --resume needs the folder of a run started by "
                     "`fralab measure`");
  }
  if (given.resume && std::holds_alternative<AutoRunRecord>(load_any_run_record(dir.run_json())))
    throw InputError(given.out + ": an auto campaign: measure() resumes it (resume_auto_campaign)");
}

MeasureRun::MeasureRun(const MeasureOptions& given) : o_(given), dir_(given.out) {
  read_options(given);
  choose_run_id_and_url();
  if (o_.resume)
    find_resume_point();
  else
    start_record();
  run_.lcm_url = url_;
  run_.state = RunRecordState::kRunning;
  save_run(o_.out, run_);
}

void MeasureRun::read_options(const MeasureOptions& given) {
  if (given.resume) {
    run_ = load_run_record(dir_.run_json());
    if (run_.state == RunRecordState::kComplete)
      throw InputError(given.out + ": the run is complete; there is nothing to resume");
    o_ = options_from_run(given.out, run_);
  }
  model_ = load_model_or_scheduled(o_.engine);
  o_.acquire.validate();
  o_.acquire.block = block_samples(model_, o_.acquire);  // run.json and every process: the number
  const std::vector<int> excite = select_inputs(model_, o_.acquire.inputs);
  fs::create_directories(dir_.frd_dir());
  fs::create_directories(dir_.logs_dir());
  if (!o_.resume) save_model(dir_.engine(), model_);  // the exact model measured, beside its tape
  // The acquisition's options from here on name the selected inputs.
  std::string inputs_csv;
  for (int i : excite) inputs_csv += (inputs_csv.empty() ? "" : ",") + model_.inputs[i].name;
  o_.acquire.inputs = inputs_csv;
  r_.pairs = measured_pairs(model_, excite);
}

void MeasureRun::choose_run_id_and_url() {
  const uint64_t salt = uint64_t(getpid()) * 1000003u ^
                        uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
  for (const auto& [kind, host] : o_.hosts)
    if (kind != "plant" && kind != "recorder" && kind != "acquire" && kind != "analyze" &&
        kind != "identify")
      throw InputError("--on " + kind + "=" + host +
                       ": no such process (plant, recorder, acquire, analyze, identify)");
  url_ = o_.lcm_url.empty() ? private_lcm_url(salt) : o_.lcm_url;
  if (!o_.hosts.empty() && o_.lcm_url.empty()) url_.replace(url_.find("ttl=0"), 5, "ttl=1");
  url_ = resolve_lcm_url(url_);  // ttl=1 needs FRALAB_NETWORK=1
  r_.run_id = o_.resume ? run_.run_id : "run-" + std::to_string(salt % 1000000007u);
}

void MeasureRun::find_resume_point() {
  const std::string tape = dir_.tape();
  const int64_t cut = cut_tape_to_whole_events(tape);
  if (cut > 0)
    std::cerr << "fralab: " << tape << ": cut " << cut << " bytes of a partly written last event\n";
  if (o_.acquire.adaptive.enabled()) {
    from_ = plan_adaptive_resume(tape, r_.run_id, model_, o_.acquire);  // the decisions taken
  } else {
    const auto camp = make_campaign(model_, o_.acquire, r_.run_id);
    from_ = plan_resume(tape, r_.run_id, *camp, o_.acquire.block);
  }
  std::cerr << "fralab: resuming run " << r_.run_id << ": " << from_.blocks_on_tape
            << " tape blocks on the tape; "
            << (from_.complete ? "every block is there"
                               : "starting again at step " + std::to_string(from_.first_step) +
                                     " (command block " + std::to_string(from_.first_block) + ")")
            << "\n";
  run_.resumed = run_.resumed.value_or(0) + 1;
}

void MeasureRun::start_record() {
  fs::remove(dir_.tape());
  run_ = RunRecord{};
  run_.run_id = r_.run_id;
  run_.engine = model_.name;
  run_.inputs = o_.acquire.inputs;
  run_.pairs = r_.pairs;
  run_.options.seed = o_.seed;
  run_.options.no_noise = o_.no_noise;
  run_.options.fit_delay = o_.fit_delay;
  if (!o_.fit) run_.options.fit = false;
  run_.options.timeout_s = o_.timeout_s;
  run_.options.stall_timeout_s = o_.stall_timeout_s;
  run_.options.hosts = o_.hosts;
  run_.options.deputy_url = o_.deputy_url;
  run_.options.acquire_flags = acquire_flags(o_.acquire);
  // The lab's measurement chain: recorded here and, through the acquisition, on the tape.
  run_.measurement_chain = emulator_chain(model_, o_.acquire.sample_rate_hz);
  run_.zoom = zoom_placement(model_, o_.acquire);
}

void MeasureRun::prepare_supervision() {
  Supervisor::catch_stop_signals();
  if (!o_.hosts.empty()) {
    const std::string durl =
        resolve_lcm_url(o_.deputy_url.empty() ? kDefaultDeputyUrl : o_.deputy_url);
    deputy_lcm_ = std::make_unique<lcm::LCM>(durl);
    require_lcm(*deputy_lcm_, "the deputies' LCM URL", durl);
    deputies_ = std::make_unique<DeputyClient>(*deputy_lcm_, r_.run_id);
    for (const auto& [kind, host] : o_.hosts) deputies_->wait_for_deputy(host, 10);
  }
  sup_.set_remote(deputies_.get());
  // The excitation stops first, actuators to their operating point.
  sup_.set_stop_first({"acquire"});
}

void MeasureRun::start_and_supervise() {
  const ProcessPlan plan = plan_processes(model_, o_, r_.run_id, url_, from_);
  if (plan.processes.empty()) return;
  // Every consumer listens before the acquisition, started last, sends its first block.
  for (size_t k = 0; k + 1 < plan.processes.size(); ++k) sup_.start(plan.processes[k]);
  const auto t0 = std::chrono::steady_clock::now();
  ProgressWatch progress(url_, r_.run_id, o_.progress, t0);
  sup_.start(plan.processes.back());
  try {
    sup_.wait_for(plan.awaited, o_.timeout_s, [&] { progress.draw(); });
  } catch (...) {
    progress.abandon();
    throw;
  }
  progress.finish();
  r_.wall_time_s = seconds_since(t0);
}

void MeasureRun::wait_for_identifier() {
  t_fit_ = std::chrono::steady_clock::now();
  if (o_.resume || !o_.fit) return;
  try {  // a failed fit leaves the measurement whole: the run ends partial
    sup_.wait_for({"identify"}, o_.timeout_s);
  } catch (const Interrupted&) {
    throw;
  } catch (const InputError& e) {
    fit_failure_ = e.what();
  }
}

void MeasureRun::verify_tape() {
  // The recorder acknowledged every tape block once on disk; the tape is read back before the
  // recorder is stopped.
  std::string problem;
  const int64_t n = read_back_tape(dir_.tape(), r_.run_id, &problem);
  sup_.stop("recorder", SIGINT, 5.0);
  if (n < 0) throw InputError(dir_.tape() + ": " + problem);
  r_.tape_blocks = n;
}

void MeasureRun::check_data() {
  DataQualityOptions dq;
  dq.noise_free = o_.no_noise;
  dq.other_runs = o_.clock_estimates;
  r_.clock_estimates = o_.clock_estimates;
  // The measurement is whole whatever the checks say: a tape they cannot read is said, not fatal.
  CheckedTape checked;
  try {
    checked = check_tape(dir_.tape(), r_.run_id, r_.pairs, dq);
  } catch (const InputError& e) {
    std::cerr << "fralab: data quality not checked: " << e.what() << "\n";
    return;
  }
  for (ClockEstimate c : checked.quality.clocks) {
    c.run = o_.out;
    r_.clock_estimates.push_back(std::move(c));
  }
  print_data_quality(checked.quality);
  run_.data_quality = std::move(checked.quality);
  mended_curves_ = std::move(checked.mended_curves);
}

void MeasureRun::analyse_resumed() {
  if (o_.resume || mended_curves_) {
    // The curves in pair order, as the live identifier takes them.
    std::vector<Frd> curves =
        mended_curves_ ? *mended_curves_ : analyze_tape_file(dir_.tape(), r_.pairs, {});
    if (o_.fit)
      fit_failure_ = save_curves_and_fit(curves, o_.out, o_.fit_delay,
                                         model_.name + ": measured transfer matrix", o_.timeout_s);
    else
      save_curves(curves, o_.out);
  }
  r_.fit_time_s = seconds_since(t_fit_);
}

InputError MeasureRun::abandon(const std::exception& e) {
  sup_.stop_all();
  const bool interrupted = dynamic_cast<const Interrupted*>(&e) != nullptr;
  run_.state = interrupted ? RunRecordState::kInterrupted : RunRecordState::kFailed;
  run_.reason = e.what();
  save_run(o_.out, run_);
  if (interrupted)
    return InputError(std::string(e.what()) +
                      ": the excitation was stopped first, then every "
                      "process; resume with `fralab measure --resume " +
                      o_.out + "`");
  return InputError(std::string(e.what()) + " (everything measured is kept in " + o_.out +
                    "; resume with `fralab measure --resume " + o_.out + "`)");
}

MeasureResult MeasureRun::finish() {
  const AcquireOptions& ao = o_.acquire;
  const auto camp = make_campaign(model_, ao, r_.run_id);
  double engine_total = double(camp->total_samples()) / ao.sample_rate_hz;
  if (fs::exists(dir_.acquire_summary())) {
    const AcquisitionSummary acq = acquisition_summary_from_json(
        json_load_file(dir_.acquire_summary()), {dir_.acquire_summary(), ""});
    // The adaptive campaign grew while running: its length is the summary's.
    if (ao.adaptive.enabled()) engine_total = double(acq.samples) / ao.sample_rate_hz;
    run_.retransmissions = acq.retransmissions;
    run_.items_retransmitted = acq.items_retransmitted;
  }
  r_.engine_time_s = engine_total;
  if (ao.adaptive.enabled()) {  // each step as decided, from the curves (a resumed run's too)
    std::vector<Frd> curves;
    for (const std::string& p : r_.pairs)
      if (const std::string f = dir_.frd(p); fs::exists(f)) curves.push_back(load_frd(f));
    const auto& adaptive = dynamic_cast<const AdaptiveSineCampaign&>(*camp);
    std::vector<int> limits;
    for (int g = 0; g < adaptive.n_steps(); ++g) limits.push_back(adaptive.limit(g));
    run_.adaptive = adaptive_steps_json(adaptive_steps(curves, ao.adaptive.sigma_target, limits));
  }
  record_fit_outcome(run_, r_, fit_failure_);
  run_.engine_time_s = r_.engine_time_s;
  run_.wall_time_s = r_.wall_time_s;
  run_.speedup = r_.engine_time_s / std::max(r_.wall_time_s, 1e-9);
  run_.tape_blocks = r_.tape_blocks;
  run_.fit_time_s = r_.fit_time_s;
  save_run(o_.out, run_);
  return r_;
}

}  // namespace fralab
