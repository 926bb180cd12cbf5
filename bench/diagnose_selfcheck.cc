// fralab-bench-diagnose: the diagnosis's randomised self-check. N random plants
// (tests/util/random_plant.h, each hiding 0-2 effects; or with --plants machine,
// tests/util/random_machine.h: shaped like real machines, 0-3 effects that may share pairs) go
// through the real processes
// (`fralab diagnose --engine`, measurement and validation included); prints per case the findings
// that were not hidden and the hidden effects that were missed, then precision (true findings /
// all findings), recall (hidden effects named at their place within tolerance / hidden) and how
// many of those found have their true value inside the finding's 2-sigma interval; for state
// plants also precision and recall at the data's resolution (a finding naming an effect's place
// whose value is beyond tolerance but whose 2-sigma interval holds the truth counted right).
// `--excitation auto` measures with the auto campaign; the summary counts the runs that completed,
// ended partial (exit status 3: measured, a later step failed) or failed.
// --plants modal (tests/util/random_modal.h: structures, light modes common to every path) is
// measured in-process: each path's exact response on a grid dense enough for its lightest mode,
// with noise of known sigma, and a validation measurement; the diagnosis runs in this process.
// --plants state (tests/util/random_state.h: state models, entries changed) likewise.
// --through-lab measures modal plants through the processes instead (outputs given noise:
// random_modal.h, set_lab_noise); --lab-flags passes more flags to `fralab diagnose` (the zoom's).
// --plants j85 (tests/util/j85_case.h): the J85 at 95 % every case, its nine findings hidden,
// measured with the lab's own band and density (--band and --points-per-decade ignored).
// --faults (machine and j85 plants): 0-2 recording faults per case (tests/util/random_faults.h) put
// into the engine's channels; the summary adds the faults named in diagnosis.json's data_quality
// (any run of the measurement), those sized within 10 %, those named but not put in, those the
// checks did not name but the diagnosis names beside a finding they explain (a data alternative:
// a clock too small to name, a dead channel, a clipping), and precision and recall over the cases
// with faults and over those without apart (a finding a fault caused is a false finding of a case
// with faults, its alternative named or not).
// Run it isolated: scripts/isolated.sh build/bin/fralab-bench-diagnose --cases 60
#include <sys/wait.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "fralab/exchange/tape_series.h"
#include "j85_case.h"
#include "random_faults.h"
#include "random_machine.h"
#include "random_modal.h"
#include "random_plant.h"
#include "random_state.h"
#include "test_util.h"

using namespace fralab;
using namespace fralab::testing;

namespace {

// Whether f names e at its place (cause, scope, entry) with a value beyond e's tolerance but e's
// true value inside f's 2-sigma interval (two_sigma_interval, as the 2-sigma figure counts it):
// sized as closely as the data allow, where they do not allow e's tolerance.
bool named_at_resolution(const HiddenEffect& e, const Finding& f) {
  HiddenEffect anywhere = e;
  anywhere.tol_abs = INFINITY;
  if (e.matches(f) || !anywhere.matches(f)) return false;
  const auto two = two_sigma_interval(f, e.param);
  return two && (*two)[0] <= e.value && e.value <= (*two)[1];
}

std::vector<Finding> read_findings(const std::string& file) {
  return findings_from_json(json_load_file(file), file);
}

// Every fault the data-quality checks named in diagnosis.json (its runs' and the diagnosis' own
// against the simulation), once per channel and kind.
std::vector<DataFault> named_faults(const std::string& file) {
  const Json j = json_load_file(file);
  std::vector<DataFault> out;
  if (!j.contains("data_quality")) return out;
  std::vector<Json> sections(j["data_quality"]["runs"].begin(), j["data_quality"]["runs"].end());
  if (j["data_quality"].contains("channels")) sections.push_back(j["data_quality"]["channels"]);
  for (const Json& r : sections) {
    const DataQuality q = data_quality_from_json(r, JsonWhere{file, "/data_quality"});
    for (const DataFault& f : q.faults) {
      bool seen = false;
      for (const DataFault& o : out) seen |= o.channel == f.channel && o.kind == f.kind;
      if (!seen) out.push_back(f);
    }
  }
  return out;
}

// The data alternatives of diagnosis.json beside its findings: (channel, kind) of each.
std::vector<std::pair<std::string, std::string>> alternatives(const std::string& file) {
  const Json j = json_load_file(file);
  std::vector<std::pair<std::string, std::string>> out;
  if (!j.contains("data_quality") || !j["data_quality"].contains("alternatives")) return out;
  for (const Json& a : j["data_quality"]["alternatives"])
    out.emplace_back(a.value("channel", ""), a.value("kind", ""));
  return out;
}

// A fault's name as a finding's data alternative (diagnose/data_faults.h), "" where none is.
std::string alternative_kind(DataFaultKind k) {
  switch (k) {
    case DataFaultKind::kClock:
      return "clock";
    case DataFaultKind::kNoResponse:
      return "dead_channel";
    case DataFaultKind::kClipping:
      return "clipping";
    default:
      return "";
  }
}

// Recording faults for case `i` of `seed`: 0, 1 or 2 (a third of the cases each), sized from a
// clean recording of the engine made in-process by the multisine the lab runs first (the same
// band, density and periods: a fault's time falls inside the run); added to `engine`.
std::vector<InjectedFault> add_faults(Model& engine, uint64_t seed, int i, const std::string& band,
                                      int ppd) {
  std::mt19937_64 g(seed * 104729 + uint64_t(i));
  const int n = std::uniform_int_distribution<int>(0, 2)(g);
  std::vector<InjectedFault> out;
  if (n == 0) return out;
  AcquireOptions o;
  o.band = band;
  o.points_per_decade = ppd;
  o.excitation = Excitation::kMultisine;
  o.min_cycles = 2;  // the auto campaign's periods per experiment
  const TimeSeries clean =
      blocks_to_series(simulate_campaign(engine, o, true, seed + uint64_t(i)).blocks, "clean");
  for (int k = 0; k < n; ++k) out.push_back(add_random_fault(engine, clean, g));
  return out;
}

// Scores one case, adds it to the totals and prints its line (and what failed).
void report(const RandomCase& c, const std::vector<Finding>& findings, Score& total, int& failing) {
  const Score s = score(c, findings);
  total.findings += s.findings;
  total.true_findings += s.true_findings;
  total.hidden += s.hidden;
  total.found += s.found;
  total.with_interval += s.with_interval;
  total.in_two_sigma += s.in_two_sigma;
  const bool ok = s.false_findings.empty() && s.missed.empty();
  failing += !ok;
  std::printf("%s: %zu inputs x %zu outputs, %d hidden, %d findings, %s\n", c.name.c_str(),
              c.simulation.inputs.size(), c.simulation.outputs.size(), s.hidden, s.findings,
              ok ? "ok" : "FAILING");
  for (const auto& f : s.false_findings) std::printf("    false: %s\n", f.c_str());
  for (const auto& m : s.missed) std::printf("    missed: %s\n", m.c_str());
  for (const auto& m : s.outside_two_sigma) std::printf("    outside 2 sigma: %s\n", m.c_str());
  std::fflush(stdout);
}

// The self-check's options (main's flags).
struct SelfCheckOptions {
  int cases = 60, first = 0;
  uint64_t seed = 1;
  std::string out = "out/selfcheck", band = "0.1:20", excitation = "stepped";
  int ppd = 5;
  double min_precision = 0, min_recall = 0;
  std::string plants = "random";
  bool faults = false, through_lab = false;
  std::string lab_flags;
};

// The cases one by one, their scores summed; summary() prints the totals.
class SelfCheck {
 public:
  explicit SelfCheck(const SelfCheckOptions& o)
      : o_(o),
        bin_(std::filesystem::canonical("/proc/self/exe").parent_path().string() + "/fralab") {}

  void run_case(int i) {
    RandomCase c = o_.plants == "machine" ? random_machine_case(o_.seed, i)
                   : o_.plants == "modal" ? random_modal_case(o_.seed, i)
                   : o_.plants == "state" ? random_state_case(o_.seed, i)
                   : o_.plants == "j85"   ? j85_case(i)
                                          : random_case(o_.seed, i);
    const std::string dir = o_.out + "/" + c.name;
    std::filesystem::create_directories(dir);
    if (o_.through_lab) set_lab_noise(c);
    save_model(dir + "/simulation.json", c.simulation);
    const std::vector<InjectedFault> injected =
        o_.faults ? add_faults(c.engine, o_.seed, i, o_.band, o_.ppd)
                  : std::vector<InjectedFault>{};
    for (const InjectedFault& f : injected)
      std::printf("%s: recording fault on %s: %s\n", c.name.c_str(), f.channel.c_str(),
                  f.text.c_str());
    save_model(dir + "/engine.json", c.engine);
    if (o_.plants == "state") return state_case(c, i, dir);
    if (o_.plants == "modal" && !o_.through_lab) {
      const Diagnosis d = diagnose(c.simulation, modal_measurement(c, o_.seed + uint64_t(i)));
      json_save_file(dir + "/diagnosis.json", diagnosis_to_json(d));
      ++complete_;
      report(c, d.findings, total_, failing_);
      return;
    }
    lab_case(c, dir, injected);
  }

  // Prints the totals; true when precision and recall reach the options' minimums.
  bool summary() const {
    if (o_.faults) print_fault_summary();
    const double precision = total_.findings ? double(total_.true_findings) / total_.findings : 1.0;
    const double recall = total_.hidden ? double(total_.found) / total_.hidden : 1.0;
    std::printf(
        "selfcheck: %d %s cases (seed %llu, band %s Hz, %d/decade): precision %.3f (%d of %d "
        "findings), "
        "recall %.3f (%d of %d hidden effects), %d failing cases; the true value inside the "
        "finding's 2-sigma interval %.3f (%d of %d found with an interval); excitation %s: %d runs "
        "complete, %d partial, %d failed\n",
        o_.cases, o_.plants.c_str(), (unsigned long long)o_.seed, o_.band.c_str(), o_.ppd,
        precision, total_.true_findings, total_.findings, recall, total_.found, total_.hidden,
        failing_, total_.with_interval ? double(total_.in_two_sigma) / total_.with_interval : 1.0,
        total_.in_two_sigma, total_.with_interval, o_.excitation.c_str(), complete_, partial_,
        failed_);
    if (o_.plants == "state") print_state_summary();
    if (!engine_s_.empty() || bound_failed_) print_bound_summary();
    return precision >= o_.min_precision && recall >= o_.min_recall;
  }

 private:
  // A state plant diagnosed in-process: scored as every case, at the data's resolution, and over
  // the entries the data resolve.
  void state_case(const RandomCase& c, int i, const std::string& dir) {
    Diagnosis d;
    try {
      d = diagnose(c.simulation, state_measurement(c, o_.seed + uint64_t(i)));
    } catch (const InputError& e) {
      std::printf("%s: the diagnosis failed: %s\n", c.name.c_str(), e.what());
      ++failed_, ++failing_;
      total_.hidden += int(c.hidden.size());
      total_.findings += 1;
      return;
    }
    json_save_file(dir + "/diagnosis.json", diagnosis_to_json(d));
    ++complete_;
    report(c, d.findings, total_, failing_);
    for (const Finding& f : d.findings) {
      ++at_resolution_.findings;
      at_resolution_.true_findings += std::any_of(
          c.hidden.begin(), c.hidden.end(),
          [&](const HiddenEffect& e) { return e.matches(f) || named_at_resolution(e, f); });
    }
    for (const HiddenEffect& e : c.hidden) {
      ++at_resolution_.hidden;
      const bool named = std::any_of(d.findings.begin(), d.findings.end(), [&](const Finding& f) {
        return e.matches(f) || named_at_resolution(e, f);
      });
      at_resolution_.found += named;
      if (named && std::none_of(d.findings.begin(), d.findings.end(),
                                [&](const Finding& f) { return e.matches(f); }))
        std::printf("    named, the truth inside its 2-sigma interval: %s\n", e.describe().c_str());
    }
    for (const HiddenEffect& e : c.hidden) {
      if (!state_effect_resolved(c, e)) {
        std::printf("    not resolved by the data: %s\n", e.describe().c_str());
        continue;
      }
      ++resolved_.hidden;
      const bool found = std::any_of(d.findings.begin(), d.findings.end(),
                                     [&](const Finding& f) { return e.matches(f); });
      resolved_.found += found;
      if (found) continue;
      // Missed, but held by a set the data fit as well (diagnosis.json's state_alternatives).
      for (const StateAlternative& a : d.state_alternatives)
        if (std::any_of(a.findings.begin(), a.findings.end(),
                        [&](const Finding& f) { return e.matches(f); })) {
          std::printf("    in an as-well-fitted set: %s\n", e.describe().c_str());
          ++in_alternatives_;
          break;
        }
    }
  }

  // A case through the lab's processes (`fralab diagnose --engine`), its exit status counted.
  void lab_case(const RandomCase& c, const std::string& dir,
                const std::vector<InjectedFault>& injected) {
    const std::string cmd = bin_ + " diagnose --simulation " + dir + "/simulation.json --engine " +
                            dir + "/engine.json --out " + dir + "/diagnosis --no-plots --band " +
                            o_.band + " --points-per-decade " + std::to_string(o_.ppd) +
                            " --excitation " + o_.excitation + " --seed 5 " + o_.lab_flags + " > " +
                            dir + "/log.txt 2>&1";
    const int st = std::system(cmd.c_str());
    const int status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    complete_ += status == 0, partial_ += status == 3;
    if (status == 3)
      std::printf("%s: partial (a step after measuring failed; see %s/log.txt)\n", c.name.c_str(),
                  dir.c_str());
    if (status != 0 && status != 3) {
      ++failed_;
      std::printf("%s: fralab diagnose failed (see %s/log.txt)\n", c.name.c_str(), dir.c_str());
      ++failing_;
      total_.hidden += int(c.hidden.size());
      total_.findings += 1;  // a failed run counts against precision too
      return;
    }
    const std::string dj = dir + "/diagnosis/diagnosis.json";
    report(c, read_findings(dj), total_, failing_);
    if (o_.faults) score_recording_faults(c, dj, injected);
    engine_time_against_bound(c, dir);
  }

  // The case's engine time against the best sine's for its findings (`fralab bound`).
  void engine_time_against_bound(const RandomCase& c, const std::string& dir) {
    const std::string json = dir + "/diagnosis/bound.json";
    const std::string cmd = bin_ + " bound --simulation " + dir + "/simulation.json --diagnosis " +
                            dir + "/diagnosis --json " + json + " > " + dir + "/bound.txt 2>&1";
    if (std::system(cmd.c_str()) != 0) {
      std::printf("%s: fralab bound failed (see %s/bound.txt)\n", c.name.c_str(), dir.c_str());
      ++bound_failed_;
      return;
    }
    const Json b = json_load_file(json);
    engine_s_.push_back(b.at("campaign_s").get<double>());
    if (b.at("status") != "ok") return;
    ratios_.push_back(b.at("ratio").get<double>());
    std::printf(
        "    engine time %.0f s, the best sine's %.1f s for the same intervals (ratio %.3g)\n",
        engine_s_.back(), b.at("bound_s").get<double>(), ratios_.back());
  }

  void print_bound_summary() const {
    auto median = [](std::vector<double> v) {
      if (v.empty()) return 0.0;
      std::sort(v.begin(), v.end());
      return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    };
    std::printf(
        "engine time: median %.0f s a case; against the bound (`fralab bound`, %zu cases with "
        "findings to bound): median ratio %.3g, %d cases without a bound\n",
        median(engine_s_), ratios_.size(), median(ratios_), bound_failed_);
  }

  // The faults put into the recording against those diagnosis.json names, and the case's score
  // apart by whether it had faults (effects at an output a fault made dead counted apart too).
  void score_recording_faults(const RandomCase& c, const std::string& dj,
                              const std::vector<InjectedFault>& injected) {
    const std::vector<DataFault> named = named_faults(dj);
    const FaultScore fs = score_faults(injected, named);
    fault_total_.add(fs);
    for (const std::string& l : fs.lines) std::printf("    fault %s\n", l.c_str());
    // A fault the checks did not name, named beside a finding it explains as well.
    const auto alts = alternatives(dj);
    for (const InjectedFault& f : injected) {
      const bool in_section = std::any_of(named.begin(), named.end(), [&](const DataFault& n) {
        return n.channel == f.channel && n.kind == f.kind;
      });
      const std::string kind = alternative_kind(f.kind);
      if (in_section || kind.empty()) continue;
      if (std::find(alts.begin(), alts.end(), std::pair{f.channel, kind}) == alts.end()) continue;
      ++beside_findings_;
      std::printf("    fault named beside a finding: %s %s\n", f.channel.c_str(), kind.c_str());
    }
    Score& part = injected.empty() ? without_faults_ : with_faults_;
    const std::vector<Finding> found = read_findings(dj);
    const Score sc = score(c, found);
    part.findings += sc.findings, part.true_findings += sc.true_findings;
    part.hidden += sc.hidden, part.found += sc.found;
    // Effects at an output that a fault made dead: the recording holds nothing of them.
    for (const HiddenEffect& e : c.hidden) {
      bool dead = false;
      for (const InjectedFault& f : injected)
        dead |= f.kind == DataFaultKind::kNoResponse && f.channel == e.output;
      if (!dead) continue;
      ++on_dead_.hidden;
      for (const Finding& f : found)
        if (e.matches(f)) {
          ++on_dead_.found;
          break;
        }
    }
  }

  void print_fault_summary() const {
    auto share = [](int a, int b) { return b ? double(a) / b : 1.0; };
    std::printf(
        "faults: named %d / %d (%.3f), sized within 10 %% %d / %d, named but not put in %d; "
        "of the others, named beside a finding they explain %d; "
        "cases with faults: precision %.3f recall %.3f (%.3f of the %d effects at outputs "
        "alive, %d of %d at dead ones found); without: precision %.3f recall %.3f\n",
        fault_total_.named, fault_total_.put, share(fault_total_.named, fault_total_.put),
        fault_total_.sized, fault_total_.to_size, fault_total_.false_named, beside_findings_,
        share(with_faults_.true_findings, with_faults_.findings),
        share(with_faults_.found, with_faults_.hidden),
        share(with_faults_.found - on_dead_.found, with_faults_.hidden - on_dead_.hidden),
        with_faults_.hidden - on_dead_.hidden, on_dead_.found, on_dead_.hidden,
        share(without_faults_.true_findings, without_faults_.findings),
        share(without_faults_.found, without_faults_.hidden));
  }

  void print_state_summary() const {
    std::printf(
        "state entries the data resolve (undone alone, chi2 beyond ln 2N): %d of %d, "
        "recall over them %.3f (%d of %d); of those missed, %d in a set the data fit as well "
        "(state_alternatives)\n",
        resolved_.hidden, total_.hidden,
        resolved_.hidden ? double(resolved_.found) / resolved_.hidden : 1.0, resolved_.found,
        resolved_.hidden, in_alternatives_);
    std::printf(
        "at the data's resolution (the value within tolerance, or the truth inside the "
        "finding's 2-sigma interval): precision %.3f (%d of %d findings), recall %.3f (%d of %d "
        "hidden effects)\n",
        at_resolution_.findings ? double(at_resolution_.true_findings) / at_resolution_.findings
                                : 1.0,
        at_resolution_.true_findings, at_resolution_.findings,
        at_resolution_.hidden ? double(at_resolution_.found) / at_resolution_.hidden : 1.0,
        at_resolution_.found, at_resolution_.hidden);
  }

  SelfCheckOptions o_;
  std::string bin_;
  FaultScore fault_total_;
  int beside_findings_ = 0;  // faults not named by the checks, named as a finding's alternative
  Score with_faults_, without_faults_, on_dead_;
  Score total_, resolved_;   // resolved: the state entries the data resolve
  Score at_resolution_;      // state plants: a value inside its 2-sigma interval counted right
  int in_alternatives_ = 0;  // resolved, missed, and in a set the data fit as well
  int failing_ = 0, complete_ = 0, partial_ = 0, failed_ = 0;
  std::vector<double> engine_s_, ratios_;  // lab cases: engine time; ratio to the bound
  int bound_failed_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-bench-diagnose: precision and recall of the diagnosis on random plants"};
  SelfCheckOptions o;
  app.add_option("--min-precision", o.min_precision, "exit 1 below this (ctest)");
  app.add_option("--min-recall", o.min_recall, "exit 1 below this (ctest)");
  app.add_option("--cases", o.cases)->capture_default_str();
  app.add_option("--first", o.first, "index of the first case")->capture_default_str();
  app.add_option("--seed", o.seed, "generator seed")->capture_default_str();
  app.add_option("--out", o.out)->capture_default_str();
  app.add_option("--band", o.band, "measure band, Hz")->capture_default_str();
  app.add_option("--points-per-decade", o.ppd)->capture_default_str();
  app.add_option("--excitation", o.excitation, "stepped or auto (any of fralab's)")
      ->capture_default_str();
  app.add_option(
         "--plants", o.plants,
         "random (tests/util/random_plant.h) or machine (random_machine.h: a slow mode in "
         "every path, shared fast dynamics, weak paths, 0-3 effects that may overlap) or "
         "modal (random_modal.h: structures, measured in-process) or state (random_state.h: "
         "state models with changed entries, measured in-process) or j85 (the J85 at 95 %, "
         "its nine findings hidden, the lab's band and density)")
      ->check(CLI::IsMember({"random", "machine", "modal", "state", "j85"}))
      ->capture_default_str();
  app.add_flag("--faults", o.faults, "machine and j85 plants: 0-2 recording faults per case");
  app.add_flag("--through-lab", o.through_lab,
               "modal plants: measured through the lab's processes as the others are (outputs "
               "with noise 0.2 % of their strongest response), not in-process");
  app.add_option("--lab-flags", o.lab_flags,
                 "more flags for `fralab diagnose` (e.g. \"--zoom-period-factor 4\", "
                 "\"--no-zoom\")");
  CLI11_PARSE(app, argc, argv);
  if (o.faults && o.plants != "machine" && o.plants != "j85")
    throw InputError("--faults needs --plants machine or j85");
  if (o.plants == "j85") o.band = "0.04:100", o.ppd = 10;  // the lab's own (fralab run's defaults)
  if (o.through_lab && o.plants != "modal") throw InputError("--through-lab needs --plants modal");
  SelfCheck check(o);
  for (int i = o.first; i < o.first + o.cases; ++i) check.run_case(i);
  return check.summary() ? 0 : 1;
}
