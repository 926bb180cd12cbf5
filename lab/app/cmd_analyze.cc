// `fralab analyze`: tape mode, offline: the pair analysers over a whole tape file.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
#include "fralab/core/measure_dir.h"
#include "tape_analysis.h"

namespace fralab {

namespace {

struct AnalyzeCommand {
  std::string log, out;
  std::vector<std::string> pairs;
  AnalyzerOptions options;
};

void run(const AnalyzeCommand& c) {
  const auto frds = analyze_tape_file(c.log, c.pairs, c.options);
  const MeasureDir out(c.out);
  std::filesystem::create_directories(out.frd_dir());
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
  c->callback([ac] { run(*ac); });
}

}  // namespace fralab
