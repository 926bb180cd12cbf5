#include "fralab/lab/data_check.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <variant>

#include "fralab/analyze/pair_analyzer.h"
#include "fralab/core/measure_dir.h"
#include "fralab/core/pair_id.h"
#include "fralab/diagnose/report.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/lab/measure.h"
#include "fralab/lab/run_record.h"
#include "fralab/lcm/tape_file.h"

namespace fralab {

namespace fs = std::filesystem;

CheckedTape check_tape(const std::string& tape, const std::string& run_id,
                       const std::vector<std::string>& pairs, const DataQualityOptions& o) {
  // The run, its series and a mended copy are held in memory together.
  std::error_code ec;
  const uintmax_t bytes = std::filesystem::file_size(tape, ec);
  if (ec) throw InputError(tape + ": cannot be read: " + ec.message());
  if (bytes > kMaxCheckedTapeBytes)
    throw InputError(tape + ": " + std::to_string(bytes / 1000000) +
                     " MB, more than the data-quality checks hold in memory (" +
                     std::to_string(kMaxCheckedTapeBytes / 1000000) + " MB)");
  const TapeRun run = read_tape_run(tape, run_id);
  const TimeSeries series = blocks_to_series(run.blocks, tape);
  const Schedule schedule{series.sample_rate_hz, run.run_id, run.events};
  CheckedTape out;
  out.quality = check_data_quality(series, schedule, o);
  if (!out.quality.changes_curves()) return out;
  const std::vector<Block> blocks = series_to_blocks(mend_series(series, out.quality, schedule),
                                                     schedule, run.blocks.front().n_samples);
  out.mended_curves = analyse_run_in_memory(schedule.events, blocks, pairs);
  widen_for_mending(*out.mended_curves, out.quality);
  return out;
}

void print_data_quality(const DataQuality& q) {
  for (const DataFault& f : q.faults)
    std::cerr << "fralab: data quality: " << f.text << "; " << f.action << "\n";
}

std::vector<std::string> pooled_clocks(const std::vector<ClockEstimate>& all,
                                       const DataQualityOptions& o) {
  std::vector<std::string> out;
  for (const auto& [ch, e] : pool_clocks(all))
    if (std::abs(e.eps) > o.clock_sigmas * e.sigma && std::abs(e.eps) > o.min_clock)
      out.push_back(ch);
  return out;
}

namespace {

bool mends_clock(const std::optional<DataQuality>& q, const std::string& channel) {
  return q && std::any_of(q->faults.begin(), q->faults.end(), [&](const DataFault& f) {
           return f.channel == channel && f.kind == DataFaultKind::kClock && f.mended;
         });
}

}  // namespace

ClockRecheck recheck_clocks(const std::string& dir, const std::vector<ClockEstimate>& all) {
  ClockRecheck out;
  const std::vector<std::string> named = pooled_clocks(all);
  const MeasureDir md(dir);
  if (named.empty() || !fs::exists(md.run_json())) return out;
  // The runs and, per run, which of DIR's curves it gave.
  const AnyRunRecord top = load_any_run_record(md.run_json());
  struct Source {
    std::string folder;
    std::function<bool(const std::string&)> gave;
  };
  std::vector<Source> sources;
  if (const auto* a = std::get_if<AutoRunRecord>(&top)) {
    const std::vector<std::string> sine_inputs = a->sine.inputs;
    auto from_sine = [sine_inputs](const std::string& pair) {
      return std::any_of(sine_inputs.begin(), sine_inputs.end(), [&](const std::string& x) {
        return pair == PairId::actuator_pair(x).str();
      });
    };
    sources.push_back(
        {a->multisine.dir, [from_sine](const std::string& p) { return !from_sine(p); }});
    if (!a->sine.dir.empty()) sources.push_back({a->sine.dir, from_sine});
    out.title = a->engine + ": measured transfer matrix (auto campaign)";
  } else {
    sources.push_back({dir, [](const std::string&) { return true; }});
    out.title = std::get<RunRecord>(top).engine + ": measured transfer matrix";
  }
  std::map<std::string, Frd> replaced;  // DIR's curves to replace, by pair
  for (const Source& src : sources) {
    const MeasureDir rd(src.folder);
    if (!fs::exists(rd.run_json()) || !fs::exists(rd.tape())) continue;
    RunRecord run = load_run_record(rd.run_json());
    std::vector<std::string> missing;
    for (const std::string& ch : named)
      if (!mends_clock(run.data_quality, ch)) missing.push_back(ch);
    if (missing.empty()) continue;
    DataQualityOptions dq;
    dq.noise_free = run.options.no_noise;
    for (const ClockEstimate& e : all)
      if (e.run != src.folder) dq.other_runs.push_back(e);
    CheckedTape checked;
    try {
      checked = check_tape(rd.tape(), run.run_id, run.pairs, dq);
    } catch (const InputError& e) {
      out.lines.push_back(src.folder + ": not checked again: " + e.what());
      continue;
    }
    std::vector<std::string> now;
    for (const std::string& ch : missing)
      if (mends_clock(checked.quality, ch)) now.push_back(ch);
    if (now.empty() || !checked.mended_curves) continue;
    for (const DataFault& f : checked.quality.faults)
      if (f.kind == DataFaultKind::kClock &&
          std::find(now.begin(), now.end(), f.channel) != now.end())
        out.lines.push_back(src.folder + ": " + f.text + "; " + f.action);
    std::vector<Frd> curves = *checked.mended_curves;
    save_curves(curves, src.folder);
    run.data_quality = std::move(checked.quality);
    save_run_record(rd.run_json(), run);
    for (const Frd& f : curves) {
      const PairId id = PairId::parse(f.pair);
      const bool touched = std::find(now.begin(), now.end(), id.e1()) != now.end() ||
                           std::find(now.begin(), now.end(), id.output) != now.end();
      if (touched && src.gave(f.pair) && fs::exists(md.frd(f.pair))) replaced[f.pair] = f;
    }
  }
  if (replaced.empty()) return out;
  for (const MeasuredPair& p : read_measured_dir(dir)) {
    const auto it = replaced.find(p.frd.pair);
    out.curves.push_back(it != replaced.end() ? it->second : p.frd);
  }
  out.replaced = int(replaced.size());
  return out;
}

std::string refit_after_recheck(const std::string& dir, ClockRecheck& r,
                                const std::string& fit_delay, double timeout_s) {
  if (r.curves.empty()) return "";
  const MeasureDir md(dir);
  const std::string failure = save_curves_and_fit(r.curves, dir, fit_delay, r.title, timeout_s);
  // DIR/run.json says how the fit ended (a failed one leaves the run partial, to resume).
  MeasureResult outcome;
  std::visit(
      [&](auto record) {
        record_fit_outcome(record, outcome, failure);
        save_run_record(md.run_json(), record);
      },
      load_any_run_record(md.run_json()));
  return dir + ": its " + std::to_string(r.replaced) + " curves at those channels replaced" +
         (failure.empty() ? ", every curve fitted again" : "; fitting again failed: " + failure);
}

}  // namespace fralab
