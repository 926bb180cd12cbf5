// `fralab fit`: identification alone, a transfer function from frequency-response data (frd JSON,
// CSV, TFNS card deck), with TFNS's root deletion and cross-plot.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
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
  bool common_poles = false, unweighted = false;
  int max_poles = -1;  // < 0: the default (FitOptions, PoleSetFitOptions)
};

// --common-poles: every --frd with one pole set (docs/formats.md §25).
void run_common(const FitCommand& c) {
  std::vector<Frd> curves;
  for (const std::string& f : c.ins) curves.push_back(read_fit_input(f).frd);
  PoleSetFitOptions o;
  if (c.max_poles > 0) o.max_poles = c.max_poles;
  const CommonPoleResult r = fit_common_poles(curves, c.ins, o, c.unweighted);
  json_save_file(c.out, common_poles_to_json(r));
  std::printf("fralab: %zu curves -> %s: %s; rms error over all %.4g\n", c.ins.size(),
              c.out.c_str(), r.fit.message.c_str(), r.rms_total);
  for (const CommonPoleCurve& k : r.curves)
    std::printf("  %s: rms error %.4g (%.3g of its rms)\n", k.source.c_str(), k.rms_error,
                k.rms_error / std::max(k.rms_value, 1e-300));
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
  c->add_option("--max-poles", fc->max_poles,
                "most poles of a pole set: with --common-poles, and when the order search reaches "
                "--max-order without an adequate fit (default 40; 0: no pole set)")
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
                "Bode cross-plot PNG: the data against the fit (and the fit after deletion)");
  c->callback([fc] { run(*fc); });
}

}  // namespace fralab
