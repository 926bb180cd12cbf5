// `fralab fit`: identification alone, a transfer function from frequency-response data (frd JSON,
// CSV, TFNS card deck), with TFNS's root deletion and cross-plot.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
#include "fralab/core/pair_id.h"
#include "fralab/diagnose/fitted_simulation.h"
#include "fralab/identify/common_poles.h"
#include "fralab/identify/fit_io.h"
#include "fralab/identify/readers.h"

namespace fralab {

namespace {

struct FitCommand {
  std::vector<std::string> ins;
  std::string in, out, delay = "auto", plot;
  std::vector<std::string> deletions;
  int max_order = -1;
  double delay_max = -1;   // < 0: FitOptions' default
  double tolerance = -1;   // < 0: estimated without sigma
  int min_num_order = -1;  // < 0: any relative degree
  bool no_noise_estimate = false;
  bool common_poles = false, unweighted = false, no_relative_floor = false;
  int max_poles = -1;              // < 0: the default (FitOptions, CommonPoleOptions)
  std::vector<std::string> pairs;  // --pair, one per --frd (--common-poles)
  std::string model_out;           // --model-out (--common-poles)
};

// The pair of each curve: --pair in order, else the file's own when it names one (a CSV names
// none: "E1:E2").
std::vector<std::string> curve_pairs(const FitCommand& c, const std::vector<Frd>& curves) {
  if (!c.pairs.empty() && c.pairs.size() != curves.size())
    throw InputError("fit: " + std::to_string(c.pairs.size()) + " --pair for " +
                     std::to_string(curves.size()) + " --frd: one each, in the same order");
  std::vector<std::string> out;
  for (size_t i = 0; i < curves.size(); ++i) {
    const std::string p = c.pairs.empty() ? curves[i].pair : c.pairs[i];
    if (p == "E1:E2" || !PairId::parse(p).path())
      throw InputError("fit: " + c.ins[i] + " names no pair (" + p +
                       "): give each curve's INPUT:OUTPUT with --pair, in the order of --frd");
    out.push_back(p);
  }
  return out;
}

// --common-poles: every --frd with one pole set (docs/formats.md §25).
void run_common(const FitCommand& c) {
  std::vector<Frd> curves;
  for (const std::string& f : c.ins) curves.push_back(read_fit_input(f).frd);
  if (!c.pairs.empty() || !c.model_out.empty()) {
    const std::vector<std::string> pairs = curve_pairs(c, curves);
    for (size_t i = 0; i < curves.size(); ++i) curves[i].pair = pairs[i];
  }
  CommonPoleOptions o;
  if (c.max_poles > 0) o.fit.max_poles = c.max_poles;
  o.unweighted = c.unweighted;
  o.relative_floor = !c.no_relative_floor;
  const CommonPoleResult r = fit_common_poles(curves, c.ins, o);
  json_save_file(c.out, common_poles_to_json(r));
  const auto physical = std::count(r.physical.begin(), r.physical.end(), true);
  std::printf("fralab: %zu curves -> %s: %s; rms error over all %.4g, rms |ln ratio| %.4g\n",
              c.ins.size(), c.out.c_str(), r.fit.message.c_str(), r.rms_total, r.rms_log_total);
  if (r.floor_taken)
    std::printf("  fitted again with each curve's relative floor (against sigma: %s)\n",
                r.fit_against_sigma.c_str());
  for (const CommonPoleCurve& k : r.curves)
    std::printf("  %s: rms error %.4g (%.3g of its rms), rms |ln ratio| %.4g\n", k.source.c_str(),
                k.rms_error, k.rms_error / std::max(k.rms_value, 1e-300), k.rms_log_error);
  if (r.diagram)
    std::printf("  %td physical modes (stabilisation diagram over %zu orders)\n", physical,
                r.diagram->rows.size());
  if (!c.model_out.empty()) {
    save_model(c.model_out, fitted_simulation(r, c.model_out));
    std::printf("  model %s (fralab-model/1, a path per curve)\n", c.model_out.c_str());
  }
  if (c.plot.empty()) return;
  if (std::filesystem::path(c.plot).extension() != ".png")
    throw InputError("--plot " + c.plot + ": the stabilisation diagram is a PNG: name it *.png");
  if (!r.diagram) return;
  if (!render_common_poles_diagram(r, c.plot))
    throw InputError("--plot " + c.plot +
                     ": gnuplot is not installed or failed (data and script written beside it)");
  std::printf("  stabilisation diagram %s\n", c.plot.c_str());
}

void run(FitCommand c) {
  if (c.common_poles) return run_common(c);
  if (c.ins.size() != 1)
    throw InputError("fit: several --frd need --common-poles (one pole set for all)");
  c.in = c.ins[0];
  const FitInput in = read_fit_input(c.in);
  FitOptions o = in.has_control ? in.options : FitOptions{};
  parse_delay_option(c.delay, &o);
  if (c.max_order > 0) o.max_den_order = c.max_order;
  if (c.delay_max >= 0) o.max_delay_s = c.delay_max;
  if (c.tolerance >= 0) o.tolerance = c.tolerance;
  if (c.min_num_order >= 0) o.min_num_order = c.min_num_order;
  if (c.no_noise_estimate) o.estimate_noise = false;
  if (c.max_poles >= 0) o.max_poles = c.max_poles;
  const FitResult r = fit_tf(in.frd.points, o);
  if (r.status == FitResult::Status::kFailed) throw InputError(c.in + ": " + r.message);
  std::vector<std::string> del = in.deletions;
  del.insert(del.end(), c.deletions.begin(), c.deletions.end());
  Tf kept;
  json_save_file(c.out, fit_output_json(r, in.frd.pair, del, &kept));
  std::printf("fralab: %s -> %s: %s\n", c.in.c_str(), c.out.c_str(), r.message.c_str());
  std::printf("  %s\n", tf_to_text(r.tf).c_str());
  if (c.plot.empty()) return;
  const std::filesystem::path png(c.plot);
  if (png.extension() != ".png")
    throw InputError("--plot " + c.plot + ": the cross-plot is a PNG: name it *.png");
  const BodePlot bp =
      fit_cross_plot(in.frd, c.in, r.tf, del.empty() ? nullptr : &kept, png.stem().string());
  const std::string dir = png.has_parent_path() ? png.parent_path().string() : ".";
  if (!render_bode_plots({bp}, dir, bp.stem + ".gp")) {
    throw InputError("--plot " + c.plot +
                     ": gnuplot is not installed or failed (data and script written beside it)");
  }
  std::printf("  cross-plot %s\n", c.plot.c_str());
}

}  // namespace

void add_fit_command(CLI::App& app) {
  auto fc = std::make_shared<FitCommand>();
  auto* c = app.add_subcommand(
      "fit", "identification alone: a transfer function from frequency-response data");
  c->add_option("--frd", fc->ins,
                "fralab-frd/1 JSON, CSV with named columns, or a TFNS card deck (several with "
                "--common-poles)")
      ->required();
  c->add_flag("--common-poles", fc->common_poles,
              "fit every --frd (one frequency grid) with one pole set: residues per curve, one "
              "criterion over all (docs/formats.md §25)");
  c->add_flag("--unweighted", fc->unweighted,
              "with --common-poles: every point of every curve weighted alike (scikit-rf's vector "
              "fitting), instead of each curve by its sigma or its estimated noise");
  c->add_flag("--no-relative-floor", fc->no_relative_floor,
              "with --common-poles: keep the fit against sigma even when it is not adequate (no "
              "second fit on each curve's relative floor)");
  c->add_option("--pair", fc->pairs,
                "with --common-poles: each curve's INPUT:OUTPUT, one per --frd in order (a CSV "
                "names none)");
  c->add_option("--model-out", fc->model_out,
                "with --common-poles: write the fit as a simulation (fralab-model/1), a path per "
                "curve named by its pair, every path with the common poles");
  c->add_option("--max-poles", fc->max_poles,
                "most poles of a pole set: with --common-poles (default 100), and when the order "
                "search reaches --max-order without an adequate fit (default 40; 0: no pole set)")
      ->check(CLI::Range(0, 400));
  c->add_option("--delay", fc->delay, "auto, none or SECONDS (subtracted)")->capture_default_str();
  c->add_option("--out", fc->out, "tf JSON (docs/formats.md §1) plus fit figures, roots, Pade sets")
      ->required();
  c->add_option("--max-order", fc->max_order, "highest denominator order");
  c->add_option("--delay-max", fc->delay_max,
                "with --delay auto: the delay is searched in [0, SECONDS] (default 0.2)")
      ->check(CLI::PositiveNumber);
  c->add_option("--tolerance", fc->tolerance,
                "data without sigma: the relative noise accepted (rms |G - G_fit| / |G|) instead "
                "of the level estimated from the data")
      ->check(CLI::PositiveNumber);
  c->add_flag("--no-noise-estimate", fc->no_noise_estimate,
              "data without sigma: TFNS's stop rule (real error E_N <= c_n) instead of the noise "
              "level estimated from the data");
  c->add_option("--min-num-order", fc->min_num_order,
                "lowest numerator order tried at each denominator order (default 0)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--delete", fc->deletions, "root deletion, e.g. P03,Z02 (TFNS P/Z cards)")
      ->delimiter(',');
  c->add_option("--plot", fc->plot,
                "Bode cross-plot PNG: the data against the fit (and the fit after deletion); with "
                "--common-poles the stabilisation diagram");
  c->callback([fc] { run(*fc); });
}

}  // namespace fralab
