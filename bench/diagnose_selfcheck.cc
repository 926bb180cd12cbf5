// fralab-bench-diagnose: the diagnosis's randomised self-check. N random plants
// (tests/util/random_plant.h, each hiding 0-2 effects; or with --plants machine,
// tests/util/random_machine.h: shaped like real machines, 0-3 effects that may share pairs) go
// through the real processes
// (`fralab diagnose --engine`, measurement and validation included); prints per case the findings
// that were not hidden and the hidden effects that were missed, then precision (true findings /
// all findings), recall (hidden effects named at their place within tolerance / hidden) and how
// many of those found have their true value inside the finding's 2-sigma interval.
// `--excitation auto` measures with the auto campaign; the summary counts the runs that completed,
// ended partial (exit status 3: measured, a later step failed) or failed.
// --plants modal (tests/util/random_modal.h: structures, light modes common to every path) is
// measured in-process: each path's exact response on a grid dense enough for its lightest mode,
// with noise of known sigma, and a validation measurement; the diagnosis runs in this process.
// --plants state (tests/util/random_state.h: state models, entries changed) likewise.
// Run it isolated: scripts/isolated.sh build/bin/fralab-bench-diagnose --cases 60
#include <sys/wait.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "random_machine.h"
#include "random_modal.h"
#include "random_plant.h"
#include "random_state.h"

using namespace fralab;
using namespace fralab::testing;

namespace {

std::vector<Finding> read_findings(const std::string& file) {
  const Json j = json_load_file(file);
  std::vector<Finding> v;
  const Json& fs = j.at("findings");
  for (size_t k = 0; k < fs.size(); ++k)
    v.push_back(finding_from_json(fs[k], JsonWhere{file, "/findings/" + std::to_string(k)}));
  return v;
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-bench-diagnose: precision and recall of the diagnosis on random plants"};
  int cases = 60, first = 0;
  uint64_t seed = 1;
  std::string out = "out/selfcheck", band = "0.1:20", excitation = "stepped";
  int ppd = 5;
  double min_precision = 0, min_recall = 0;
  app.add_option("--min-precision", min_precision, "exit 1 below this (ctest)");
  app.add_option("--min-recall", min_recall, "exit 1 below this (ctest)");
  app.add_option("--cases", cases)->capture_default_str();
  app.add_option("--first", first, "index of the first case")->capture_default_str();
  app.add_option("--seed", seed, "generator seed")->capture_default_str();
  app.add_option("--out", out)->capture_default_str();
  app.add_option("--band", band, "measure band, Hz")->capture_default_str();
  app.add_option("--points-per-decade", ppd)->capture_default_str();
  app.add_option("--excitation", excitation, "stepped or auto (any of fralab's)")
      ->capture_default_str();
  std::string plants = "random";
  app.add_option(
         "--plants", plants,
         "random (tests/util/random_plant.h) or machine (random_machine.h: a slow mode in "
         "every path, shared fast dynamics, weak paths, 0-3 effects that may overlap) or "
         "modal (random_modal.h: structures, measured in-process) or state (random_state.h: "
         "state models with changed entries, measured in-process)")
      ->check(CLI::IsMember({"random", "machine", "modal", "state"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::string bin =
      std::filesystem::canonical("/proc/self/exe").parent_path().string() + "/fralab";
  Score total;
  int failing = 0, complete = 0, partial = 0, failed = 0;
  for (int i = first; i < first + cases; ++i) {
    const RandomCase c = plants == "machine" ? random_machine_case(seed, i)
                         : plants == "modal" ? random_modal_case(seed, i)
                         : plants == "state" ? random_state_case(seed, i)
                                             : random_case(seed, i);
    const std::string dir = out + "/" + c.name;
    std::filesystem::create_directories(dir);
    save_model(dir + "/simulation.json", c.simulation);
    save_model(dir + "/engine.json", c.engine);
    if (plants == "state") {
      Diagnosis d;
      try {
        d = diagnose(c.simulation, state_measurement(c, seed + uint64_t(i)));
      } catch (const InputError& e) {
        std::printf("%s: the diagnosis failed: %s\n", c.name.c_str(), e.what());
        ++failed, ++failing;
        total.hidden += int(c.hidden.size());
        total.findings += 1;
        continue;
      }
      json_save_file(dir + "/diagnosis.json", diagnosis_to_json(d));
      ++complete;
      report(c, d.findings, total, failing);
      continue;
    }
    if (plants == "modal") {
      const Diagnosis d = diagnose(c.simulation, modal_measurement(c, seed + uint64_t(i)));
      json_save_file(dir + "/diagnosis.json", diagnosis_to_json(d));
      ++complete;
      report(c, d.findings, total, failing);
      continue;
    }
    const std::string cmd = bin + " diagnose --simulation " + dir + "/simulation.json --engine " +
                            dir + "/engine.json --out " + dir + "/diagnosis --no-plots --band " +
                            band + " --points-per-decade " + std::to_string(ppd) +
                            " --excitation " + excitation + " --seed 5 > " + dir + "/log.txt 2>&1";
    const int st = std::system(cmd.c_str());
    const int status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    complete += status == 0, partial += status == 3;
    if (status == 3)
      std::printf("%s: partial (a step after measuring failed; see %s/log.txt)\n", c.name.c_str(),
                  dir.c_str());
    if (status != 0 && status != 3) {
      ++failed;
      std::printf("%s: fralab diagnose failed (see %s/log.txt)\n", c.name.c_str(), dir.c_str());
      ++failing;
      total.hidden += int(c.hidden.size());
      total.findings += 1;  // a failed run counts against precision too
      continue;
    }
    report(c, read_findings(dir + "/diagnosis/diagnosis.json"), total, failing);
  }
  const double precision = total.findings ? double(total.true_findings) / total.findings : 1.0;
  const double recall = total.hidden ? double(total.found) / total.hidden : 1.0;
  std::printf(
      "selfcheck: %d %s cases (seed %llu, band %s Hz, %d/decade): precision %.3f (%d of %d "
      "findings), "
      "recall %.3f (%d of %d hidden effects), %d failing cases; the true value inside the "
      "finding's 2-sigma interval %.3f (%d of %d found with an interval); excitation %s: %d runs "
      "complete, %d partial, %d failed\n",
      cases, plants.c_str(), (unsigned long long)seed, band.c_str(), ppd, precision,
      total.true_findings, total.findings, recall, total.found, total.hidden, failing,
      total.with_interval ? double(total.in_two_sigma) / total.with_interval : 1.0,
      total.in_two_sigma, total.with_interval, excitation.c_str(), complete, partial, failed);
  return precision >= min_precision && recall >= min_recall ? 0 : 1;
}
