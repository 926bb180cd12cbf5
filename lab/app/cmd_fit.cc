// `fralab fit`: identification alone, a transfer function from frequency-response data (frd JSON,
// CSV, TFNS card deck), with TFNS's root deletion and cross-plot.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
#include "fralab/identify/fit_io.h"
#include "fralab/identify/readers.h"

namespace fralab {

namespace {

struct FitCommand {
  std::string in, out, delay = "auto", plot;
  std::vector<std::string> deletions;
  int max_order = -1;
  double delay_max = -1;   // < 0: FitOptions' default
  double tolerance = -1;   // < 0: estimated without sigma
  int min_num_order = -1;  // < 0: any relative degree
  bool no_noise_estimate = false;
};

void run(const FitCommand& c) {
  const FitInput in = read_fit_input(c.in);
  FitOptions o = in.has_control ? in.options : FitOptions{};
  parse_delay_option(c.delay, &o);
  if (c.max_order > 0) o.max_den_order = c.max_order;
  if (c.delay_max >= 0) o.max_delay_s = c.delay_max;
  if (c.tolerance >= 0) o.tolerance = c.tolerance;
  if (c.min_num_order >= 0) o.min_num_order = c.min_num_order;
  if (c.no_noise_estimate) o.estimate_noise = false;
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
  c->add_option("--frd", fc->in, "fralab-frd/1 JSON, CSV with named columns, or a TFNS card deck")
      ->required();
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
