// fralab-bench-plant: writes a random machine-shaped plant (tests/util/random_machine.h) of a given
// size, its engine and its simulation, for the throughput bench (bench/throughput.sh: a test
// cell's dozens of channels).
//   fralab-bench-plant --inputs 4 --outputs 16 --out DIR   # DIR/engine.json, DIR/simulation.json
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "random_machine.h"

using namespace fralab;

int main(int argc, char** argv) {
  CLI::App app{"fralab-bench-plant: a random plant of a given size"};
  int inputs = 2, outputs = 2, hidden = 0;
  uint64_t seed = 1;
  std::string out;
  app.add_option("--inputs", inputs)->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--outputs", outputs)->check(CLI::Range(1, 256))->capture_default_str();
  app.add_option("--hidden", hidden, "effects hidden in the engine")->capture_default_str();
  app.add_option("--seed", seed)->capture_default_str();
  app.add_option("--out", out)->required();
  CLI11_PARSE(app, argc, argv);
  const testing::RandomCase c = testing::random_machine_case(seed, 0, hidden, inputs, outputs);
  std::filesystem::create_directories(out);
  save_model(out + "/engine.json", c.engine);
  save_model(out + "/simulation.json", c.simulation);
  std::printf("%s: %d inputs x %d outputs, %zu paths, %zu hidden effects\n", out.c_str(), inputs,
              outputs, c.engine.paths.size(), c.hidden.size());
  return 0;
}
