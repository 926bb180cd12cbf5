// `fralab analyze`: tape mode, offline: the pair analysers over a whole tape file.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "commands.h"
#include "fralab/core/measure_dir.h"
#include "fralab/lab/data_check.h"
#include "tape_analysis.h"

namespace fralab {

namespace {

struct AnalyzeCommand {
  std::string log, out;
  std::vector<std::string> pairs;
  AnalyzerOptions options;
  bool check = true;
};

void run(const AnalyzeCommand& c) {
  const MeasureDir out(c.out);
  std::filesystem::create_directories(out.frd_dir());
  // The data checked first; a tape with a missing block is analysed as it is (its windows there
  // invalid, naming the gap).
  std::optional<std::vector<Frd>> mended;
  if (c.check) {
    try {
      CheckedTape checked = check_tape(c.log, "", c.pairs);
      print_data_quality(checked.quality);
      json_save_file(c.out + "/data_quality.json", data_quality_to_json(checked.quality));
      if (c.options.input.empty()) mended = std::move(checked.mended_curves);
    } catch (const InputError& e) {
      std::fprintf(stderr, "fralab: data quality not checked: %s\n", e.what());
    }
  }
  const auto frds = mended ? *mended : analyze_tape_file(c.log, c.pairs, c.options);
  for (const Frd& f : frds) save_frd(out.frd(f.pair), f);
  std::printf("fralab: analysed %zu pairs from %s into %s/frd\n", frds.size(), c.log.c_str(),
              c.out.c_str());
}

}  // namespace

void add_analyze_command(CLI::App& app) {
  auto ac = std::make_shared<AnalyzeCommand>();
  auto* c = app.add_subcommand("analyze", "tape mode, offline: analyse pairs from a tape file");
  c->add_option("--log", ac->log, "tape (LCM log)")->required();
  c->add_option("--pair", ac->pairs, "E1:E2, repeatable")->required();
  c->add_option("--out", ac->out, "writes OUT/frd/<E1>_<E2>.json")->required();
  c->add_option("--input", ac->options.input, "only steps exciting this input");
  c->add_flag("!--no-check", ac->check,
              "do not check the data (OUT/data_quality.json) nor analyse the mended series");
  c->callback([ac] { run(*ac); });
}

}  // namespace fralab
