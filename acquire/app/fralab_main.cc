// fralab: the one driver. Subcommands spawn the module executables as separate processes talking
// LCM (run, measure) or run a module's library directly on files (analyze --log). Exit status 0 on
// success, non-zero with a one-line reason on stderr otherwise.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "diagnose_cmd.h"
#include "fralab/identify/fit_io.h"
#include "fralab/identify/readers.h"
#include "fralab/plant/embedded_models.h"
#include "lab.h"
#include "tape_analysis.h"

using namespace fralab;

namespace {

void add_measure_flags(CLI::App* c, MeasureOptions& m) {
  c->add_option("--input", m.inputs, "input(s) NAME[,NAME...] (default: all)");
  c->add_option("--band", m.band, "LO_HZ:HI_HZ")->capture_default_str();
  c->add_option("--excitation", m.excitation, "stepped, sweep or multisine (all inputs at once)")
      ->capture_default_str();
  c->add_option("--multisine-phases", m.multisine_phases, "schroeder or random")
      ->capture_default_str();
  c->add_flag("--odd-lines", m.odd_lines, "multisine: odd harmonics only");
  c->add_option("--points-per-decade", m.points_per_decade)->capture_default_str();
  c->add_option("--amplitude-pct", m.amplitude_pct, "% of full scale (default: per input, 2)");
  c->add_option("--seed", m.seed, "plant noise seed")->capture_default_str();
  c->add_option("--amplitude-scale", m.amplitude_scale, "multiplies every input's amplitude")
      ->capture_default_str();
  c->add_option("--speed", m.speed, "1 = real time, 0 = as fast as possible")
      ->capture_default_str();
  c->add_option("--sample-rate", m.sample_rate_hz, "Hz")->capture_default_str();
  c->add_option("--min-cycles", m.min_cycles)->capture_default_str();
  c->add_option("--min-integrate-s", m.min_integrate_s)->capture_default_str();
  c->add_option("--lcm-url", m.lcm_url, "LCM URL (default: a private one per run)");
  c->add_flag("--no-noise", m.no_noise, "plant noise off");
}

// Channels, block sequence (gaps named), excitation states and events per LCM channel.
Json tape_summary(const std::string& path) {
  Json j{{"file", path}, {"events", Json::object()}, {"states", Json::object()}};
  std::vector<int64_t> seqs;
  std::vector<std::string> channels;
  bool final_block = false;
  int64_t samples = 0;
  double fs = 0;
  read_tape_file(path, [&](const TapeEvent& ev) {
    j["events"][ev.channel] = j["events"].value(ev.channel, 0) + 1;
    lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
    try {
      if (ev.channel == kTapeChannel) {
        Block b = from_msg(decode_checked<tape_block_t>(&rb, ev.channel));
        seqs.push_back(b.seq);
        if (channels.empty()) channels = b.channels;
        final_block |= b.final_block;
        samples += b.n_samples;
        fs = b.sample_rate_hz;
      } else if (ev.channel == kStatusChannel) {
        StatusEvent e = from_msg(decode_checked<excitation_status_t>(&rb, ev.channel));
        j["states"][e.state] = j["states"].value(e.state, 0) + 1;
      }
    } catch (const InputError& e) {
      throw InputError(path + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
    }
  });
  std::sort(seqs.begin(), seqs.end());
  Json gaps = Json::array();
  for (size_t i = 1; i < seqs.size(); ++i) {
    for (int64_t q = seqs[i - 1] + 1; q < seqs[i]; ++q) gaps.push_back(q);
  }
  j["channels"] = channels;
  j["tape_blocks"] = seqs.size();
  j["first_seq"] = seqs.empty() ? -1 : seqs.front();
  j["last_seq"] = seqs.empty() ? -1 : seqs.back();
  j["missing_seqs"] = gaps;
  j["final_block"] = final_block;
  j["samples"] = samples;
  j["sample_rate_hz"] = fs;
  j["engine_time_s"] = fs > 0 ? samples / fs : 0.0;
  return j;
}

void print_measure(const MeasureResult& r, const std::string& out) {
  std::printf(
      "fralab: %zu pairs measured; engine time %.0f s (%.2f h), wall time %.1f s (%.0fx); tape "
      "%s/tape.lcmlog (%lld blocks); frd in %s/frd\n",
      r.pairs.size(), r.engine_time_s, r.engine_time_s / 3600, r.wall_time_s,
      r.engine_time_s / std::max(r.wall_time_s, 1e-9), out.c_str(), (long long)r.tape_blocks,
      out.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab: frequency-response identification lab (J85-13 by default)"};
  app.require_subcommand(1);

  MeasureOptions run_opt;
  run_opt.out = "out/lab";
  auto* run =
      app.add_subcommand("run", "the lab end to end on an engine (default: embedded J85 95 %)");
  run->add_option("--engine", run_opt.engine, "engine model file or embedded name")
      ->capture_default_str();
  run->add_option("--out", run_opt.out)->capture_default_str();
  std::string run_sim;
  run->add_option(
      "--simulation", run_sim,
      "diagnose against this simulation (default: the engine's _sim model when embedded)");
  add_measure_flags(run, run_opt);

  MeasureOptions mo;
  auto* measure =
      app.add_subcommand("measure", "plant, acquisition, analysers: tape and frd files");
  measure->add_option("--engine", mo.engine, "engine model file or embedded name")->required();
  measure->add_option("--out", mo.out)->required();
  add_measure_flags(measure, mo);

  std::string log, out;
  std::vector<std::string> pairs;
  AnalyzerOptions aopt;
  auto* analyze =
      app.add_subcommand("analyze", "tape mode, offline: analyse pairs from a tape file");
  analyze->add_option("--log", log, "tape (LCM log)")->required();
  analyze->add_option("--pair", pairs, "E1:E2, repeatable")->required();
  analyze->add_option("--out", out, "writes OUT/frd/<E1>_<E2>.json")->required();
  analyze->add_option("--input", aopt.input, "only steps exciting this input");

  std::string fit_in, fit_out, fit_delay = "auto", deletions;
  int max_order = -1;
  auto* fit = app.add_subcommand(
      "fit", "identification alone: a transfer function from frequency-response data");
  fit->add_option("--frd", fit_in, "fralab-frd/1 JSON, CSV with named columns, or a TFNS card deck")
      ->required();
  fit->add_option("--delay", fit_delay, "auto, none or SECONDS (subtracted)")
      ->capture_default_str();
  fit->add_option("--out", fit_out, "tf JSON (contracts 1) plus fit figures, roots, Pade sets")
      ->required();
  fit->add_option("--max-order", max_order, "highest denominator order");
  fit->add_option("--delete", deletions, "root deletion, e.g. P03,Z02 (TFNS P/Z cards)");
  std::string fit_plot;
  fit->add_option("--plot", fit_plot,
                  "Bode cross-plot PNG: the data against the fit (and the fit after deletion)");

  DiagnoseCommand dc;
  auto* diag =
      app.add_subcommand("diagnose", "what the simulation gets wrong, why, and the extended model");
  diag->add_option("--simulation", dc.simulation,
                   "the simulation (fralab-model/1 file or embedded name)")
      ->required();
  diag->add_option("--engine", dc.engine,
                   "measure this engine model first (every flag of measure applies)");
  diag->add_option("--measured", dc.measured, "or: a measure output folder");
  diag->add_option("--out", dc.out)->required();
  diag->add_flag("!--no-plots", dc.plots, "skip the gnuplot figures");
  add_measure_flags(diag, dc.measure);

  std::string info_log;
  auto* tape = app.add_subcommand(
      "tape", "summarise a tape: channels, blocks, gaps, excitation states (JSON)");
  tape->add_option("--log", info_log, "tape (LCM log)")->required();

  CLI11_PARSE(app, argc, argv);
  try {
    if (*run) {
      // The lab end to end: the diagnosis measures the engine (and once more for validation),
      // identifies every path, and compares with the simulation.
      std::string sim = run_sim;
      if (sim.empty()) {
        std::string base = std::filesystem::path(run_opt.engine).stem().string();
        for (const auto& e : embedded_models())
          if (std::string(e.name) == base + "_sim.json") sim = base + "_sim";
      }
      if (sim.empty()) {
        MeasureResult r = run_measure(run_opt);
        print_measure(r, run_opt.out);
      } else {
        DiagnoseCommand d;
        d.simulation = sim;
        d.engine = run_opt.engine;
        d.out = run_opt.out;
        d.measure = run_opt;
        std::printf("fralab: measuring %s and diagnosing %s ...\n", run_opt.engine.c_str(),
                    sim.c_str());
        std::string summary = run_diagnose(d);
        Json rj = json_load_file(run_opt.out + "/measure/run.json");
        std::printf(
            "fralab: engine time %.0f s (%.2f h) measured in %.1f s (%.0fx), tape "
            "%s/measure/tape.lcmlog, transfer matrix %s/measure/transfer_matrix.md\n",
            rj["engine_time_s"].get<double>(), rj["engine_time_s"].get<double>() / 3600,
            rj["wall_time_s"].get<double>(), rj["speedup"].get<double>(), run_opt.out.c_str(),
            run_opt.out.c_str());
        std::printf("fralab: %s\n", summary.c_str());
      }
    } else if (*measure) {
      MeasureResult r = run_measure(mo);
      print_measure(r, mo.out);
    } else if (*diag) {
      std::printf("fralab: %s\n", run_diagnose(dc).c_str());
    } else if (*fit) {
      FitInput in = read_fit_input(fit_in);
      FitOptions o = in.has_control ? in.options : FitOptions{};
      parse_delay_option(fit_delay, &o);
      if (max_order > 0) o.max_den_order = max_order;
      FitResult r = fit_tf(in.frd.points, o);
      if (r.status == FitResult::Status::kFailed) throw InputError(fit_in + ": " + r.message);
      std::vector<std::string> del = in.deletions;
      for (size_t a = 0; a < deletions.size();) {
        size_t b = deletions.find(',', a);
        if (b == std::string::npos) b = deletions.size();
        if (b > a) del.push_back(deletions.substr(a, b - a));
        a = b + 1;
      }
      Json j = fit_to_json(r, in.frd.pair);
      const Tf kept = del.empty() ? r.tf : delete_roots(r.tf, del);
      if (!del.empty()) {
        j["deleted"] = del;
        j["zeros"] = tf_to_json(kept)["zeros"];
        j["poles"] = tf_to_json(kept)["poles"];
      }
      json_save_file(fit_out, j);
      std::printf("fralab: %s -> %s: %s\n", fit_in.c_str(), fit_out.c_str(), r.message.c_str());
      std::printf("  %s\n", tf_to_text(r.tf).c_str());
      if (!fit_plot.empty()) {
        const std::filesystem::path png(fit_plot);
        if (png.extension() != ".png")
          throw InputError("--plot " + fit_plot + ": the cross-plot is a PNG: name it *.png");
        const BodePlot bp = fit_cross_plot(in.frd, fit_in, r.tf, del.empty() ? nullptr : &kept,
                                           png.stem().string());
        const std::string dir = png.has_parent_path() ? png.parent_path().string() : ".";
        if (!render_bode_plots({bp}, dir, bp.stem + ".gp")) {
          throw InputError(
              "--plot " + fit_plot +
              ": gnuplot is not installed or failed (data and script written beside it)");
        }
        std::printf("  cross-plot %s\n", fit_plot.c_str());
      }
    } else if (*tape) {
      std::printf("%s\n", tape_summary(info_log).dump(2).c_str());
    } else if (*analyze) {
      auto frds = analyze_tape_file(log, pairs, aopt);
      std::filesystem::create_directories(out + "/frd");
      for (const Frd& f : frds) save_frd(out + "/frd/" + pair_file_stem(f.pair) + ".json", f);
      std::printf("fralab: analysed %zu pairs from %s into %s/frd\n", frds.size(), log.c_str(),
                  out.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fralab: %s\n", e.what());
    return 1;
  }
}
