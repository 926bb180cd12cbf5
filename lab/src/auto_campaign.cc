#include "fralab/lab/auto_campaign.h"

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "fralab/acquire/model_info.h"
#include "fralab/core/frd.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/pair_id.h"
#include "fralab/diagnose/report.h"
#include "fralab/envelope/envelope.h"
#include "fralab/lab/run_lock.h"
#include "fralab/lab/run_record.h"
#include "fralab/plant/embedded_models.h"

namespace fralab {

namespace fs = std::filesystem;

void AutoCampaignOptions::validate() const {
  if (multisine_periods < 2) throw InputError("auto campaign: multisine_periods must be >= 2");
  if (!(nl_threshold > 0)) throw InputError("auto campaign: nl_threshold must be > 0");
  if (!(max_rel_sigma > 0)) throw InputError("auto campaign: max_rel_sigma must be > 0");
  if (sine_points_per_decade < 1)
    throw InputError("auto campaign: sine_points_per_decade must be >= 1");
  if (sine_min_cycles < 2) throw InputError("auto campaign: sine_min_cycles must be >= 2");
  if (!(sine_settle_cycles >= 0))
    throw InputError("auto campaign: sine_settle_cycles must be >= 0");
}

double actuator_distortion(const Frd& f, double max_rel_sigma) {
  std::vector<double> nl;
  for (const FrdPoint& p : f.points)
    if (p.valid && p.nl_rel >= 0 && p.sigma > 0 && p.mag > 0 && p.sigma < max_rel_sigma * p.mag)
      nl.push_back(p.nl_rel);
  if (nl.empty()) return -1;
  std::sort(nl.begin(), nl.end());
  const size_t n = nl.size();
  return n % 2 ? nl[n / 2] : 0.5 * (nl[n / 2 - 1] + nl[n / 2]);
}

namespace {

// Step 2: the actuators that distort at the multisine's level (the median nl_rel of u_X:X in the
// multisine's folder above a.nl_threshold) into res.sine_inputs, every input's figure into res.nl;
// returns the slowest time constant of those actuators (s).
double distorting_actuators(const Model& model, const std::vector<int>& excite,
                            const std::string& multisine_dir, const AutoCampaignOptions& a,
                            AutoCampaignResult& res) {
  double act_tc = 0;
  for (int i : excite) {
    const std::string x = model.inputs[i].name;
    const std::string file = MeasureDir(multisine_dir).frd(PairId::actuator_pair(x).str());
    const double nl = fs::exists(file) ? actuator_distortion(load_frd(file), a.max_rel_sigma) : -1;
    res.nl[x] = nl;
    if (nl > a.nl_threshold) {
      res.sine_inputs.push_back(x);
      if (model.inputs[i].actuator)
        act_tc = std::max(act_tc, slowest_time_constant_s(*model.inputs[i].actuator));
    }
  }
  return act_tc;
}

// Step 3: the stepped sine for res.sine_inputs at their test amplitude, into opt.out/sine, from
// the plain runs' options; the multisine's clock estimates go to its two-cycle steps.
MeasureResult actuator_sine(const MeasureOptions& plain, const MeasureOptions& opt,
                            const AutoCampaignOptions& a, const AutoCampaignResult& res,
                            double act_tc, const MeasureResult& mr) {
  std::string sine_inputs;
  for (const std::string& x : res.sine_inputs) sine_inputs += (sine_inputs.empty() ? "" : ",") + x;
  MeasureOptions s = plain;
  s.acquire.excitation = Excitation::kStepped;
  s.acquire.inputs = sine_inputs;
  s.acquire.points_per_decade = a.sine_points_per_decade;
  s.acquire.min_cycles = a.sine_min_cycles;
  s.acquire.min_integrate_s = 0;
  s.acquire.settle_cycles = a.sine_settle_cycles;
  s.acquire.slowest_time_constant_s = act_tc;
  s.acquire.zoom.clear();    // the zoom places multisine lines
  s.seed = opt.seed + 1000;  // its own noise
  s.out = opt.out + "/sine";
  s.clock_estimates = mr.clock_estimates;  // two-cycle steps see no clock of their own
  return run_measure(s);
}

// Step 4: the sine's actuator curves replace the multisine's; the multisine's u_X:O of those
// inputs go.
std::vector<Frd> merged_curves(const std::vector<Frd>& curves, const AutoCampaignResult& res,
                               const std::string& sine_dir) {
  auto input_of_command_pair = [](const std::string& pair) {  // "u_X:..." -> X
    const PairId id = PairId::parse(pair);
    return id.command ? id.input : std::string();
  };
  std::vector<Frd> merged;
  for (const Frd& f : curves) {
    const std::string x = input_of_command_pair(f.pair);
    if (std::find(res.sine_inputs.begin(), res.sine_inputs.end(), x) == res.sine_inputs.end())
      merged.push_back(f);
  }
  for (const std::string& x : res.sine_inputs)
    merged.push_back(load_frd(MeasureDir(sine_dir).frd(PairId::actuator_pair(x).str())));
  return merged;
}

// The campaign's run.json: both runs, each input's distortion and how it was measured, the fit
// (its outcome recorded in res.measure too).
void save_auto_record(const MeasureOptions& opt, const Model& model, const AutoCampaignOptions& a,
                      AutoCampaignResult& res, const std::string& multisine_dir,
                      const RunRecord& mrun, const std::string& fit_failure) {
  AutoRunRecord run;
  record_fit_outcome(run, res.measure, fit_failure);
  run.fit_delay = opt.fit_delay;
  run.engine = model.name;
  run.seed = opt.seed;
  run.engine_time_s = res.measure.engine_time_s;
  run.wall_time_s = res.measure.wall_time_s;
  run.speedup = res.measure.engine_time_s / std::max(res.measure.wall_time_s, 1e-9);
  run.multisine = {multisine_dir, res.multisine_engine_s};
  run.sine = {opt.out + "/sine", res.sine_engine_s, res.sine_inputs};
  for (const auto& [x, v] : res.nl)
    run.inputs[x] = {
        v, std::find(res.sine_inputs.begin(), res.sine_inputs.end(), x) != res.sine_inputs.end()
               ? "sine"
               : "multisine"};
  run.nl_threshold = a.nl_threshold;
  run.measurement_chain = mrun.measurement_chain;
  run.pairs = res.measure.pairs;
  save_run_record(MeasureDir(opt.out).run_json(), run);
}

}  // namespace

AutoCampaignResult run_auto_campaign(const MeasureOptions& opt, const AutoCampaignOptions& a) {
  a.validate();
  if (opt.out.empty()) throw InputError("--out DIR is required");
  if (opt.resume)
    throw InputError(
        "--resume: an auto campaign resumes its runs one by one: `fralab measure "
        "--resume " +
        opt.out + "/multisine` (or /sine)");
  const Model model = load_model_or_scheduled(opt.engine);
  const std::vector<int> excite = select_inputs(model, opt.acquire.inputs);
  AutoCampaignResult res;
  // The campaign's folder is its own until it ends (each run below takes its own sub-folder too).
  const RunLock lock(opt.out, "fralab measure --excitation auto");
  MeasureOptions plain = opt;  // the campaign's runs are plain ones
  plain.auto_campaign = false;
  plain.fit = false;  // their curves, merged, are fitted once below
  // 1. The orthogonal multisine over every selected input.
  MeasureOptions m = plain;
  m.acquire.excitation = Excitation::kMultisine;
  m.acquire.multisine_design = MultisineOptions::Design::kOrthogonal;
  m.acquire.min_cycles = a.multisine_periods;
  m.out = opt.out + "/multisine";
  const MeasureResult mr = run_measure(m);
  res.multisine_engine_s = mr.engine_time_s;
  const RunRecord mrun = load_run_record(MeasureDir(m.out).run_json());
  // 2. Which actuators distort at the multisine's level; 3. a stepped sine for those; 4. merged.
  const double act_tc = distorting_actuators(model, excite, m.out, a, res);
  std::vector<Frd> curves;
  for (const MeasuredPair& p : read_measured_dir(m.out)) curves.push_back(p.frd);
  std::optional<RunRecord> sine_run;
  std::vector<ClockEstimate> clocks = mr.clock_estimates;  // the runs' own, for a later run
  if (!res.sine_inputs.empty()) {
    const MeasureResult sr = actuator_sine(plain, opt, a, res, act_tc, mr);
    clocks = sr.clock_estimates;
    res.sine_engine_s = sr.engine_time_s;
    sine_run = load_run_record(MeasureDir(opt.out + "/sine").run_json());
    curves = merged_curves(curves, res, opt.out + "/sine");
  }
  // DIR/frd holds exactly the merged curves: an earlier run's frd files there go (its tapes stay).
  const MeasureDir dir(opt.out);
  if (fs::exists(dir.frd_dir()))
    for (const auto& e : fs::directory_iterator(dir.frd_dir()))
      if (e.path().extension() == ".json") fs::remove(e.path());
  save_model(dir.engine(), model);
  const std::string fit_failure =
      save_curves_and_fit(curves, opt.out, opt.fit_delay,
                          model.name + ": measured transfer matrix (auto campaign)", opt.timeout_s);
  res.measure = mr;
  res.measure.clock_estimates = std::move(clocks);
  res.measure.pairs.clear();
  for (const Frd& f : curves) res.measure.pairs.push_back(f.pair);
  res.measure.engine_time_s = res.multisine_engine_s + res.sine_engine_s;
  res.measure.wall_time_s = mr.wall_time_s + (sine_run ? sine_run->wall_time_s.value_or(0.0) : 0.0);
  res.measure.tape_blocks =
      mr.tape_blocks + (sine_run ? sine_run->tape_blocks.value_or(int64_t(0)) : 0);
  save_auto_record(opt, model, a, res, m.out, mrun, fit_failure);
  return res;
}

MeasureResult resume_auto_campaign(const std::string& dir) {
  const RunLock lock(dir, "fralab measure --resume");
  AutoRunRecord run = load_auto_run_record(MeasureDir(dir).run_json());
  if (run.state == RunRecordState::kComplete)
    throw InputError(dir + ": the run is complete; there is nothing to resume");
  if (run.state != RunRecordState::kPartial)
    throw InputError(dir + "/run.json: an auto campaign in state \"" + to_string(run.state) +
                     "\": it resumes its runs one by one: `fralab measure --resume " + dir +
                     "/multisine` (or /sine)");
  std::vector<Frd> curves;
  for (const MeasuredPair& p : read_measured_dir(dir)) curves.push_back(p.frd);
  const Model model = load_model(MeasureDir(dir).engine());
  MeasureResult r;
  for (const Frd& f : curves) r.pairs.push_back(f.pair);
  r.engine_time_s = run.engine_time_s;
  r.wall_time_s = run.wall_time_s;
  std::cerr << "fralab: resuming the auto campaign in " << dir << ": fitting its " << curves.size()
            << " curves again\n";
  const std::string fit_failure =
      save_curves_and_fit(curves, dir, run.fit_delay.value_or("auto"),
                          model.name + ": measured transfer matrix (auto campaign)");
  record_fit_outcome(run, r, fit_failure);
  run.resumed = run.resumed.value_or(0) + 1;
  save_run_record(MeasureDir(dir).run_json(), run);
  return r;
}

}  // namespace fralab
