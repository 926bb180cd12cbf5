// fralab-bench-envelope: the envelope's randomised self-check. Per case a random plant of the
// diagnosis' self-check (tests/util/random_plant.h) with one or two hidden effects is made at 3-5
// operating points (speed_pct from 60 to 100): each hidden effect's parameter follows a drawn
// power law v0 (x / 80)^p (|p| 0.5-1.5: the parameter changes by a third to a half and more across
// the envelope), and every path's gain, in the engine and the simulation alike, a drawn power law
// of its own. `fralab envelope` measures and diagnoses every point through the real processes and
// joins them. A hidden effect's law comes back when the finding at its place has a law whose
// slope over the envelope, (law(x_max) - law(x_min)) / (x_max - x_min), lies within 2 sigma of the
// truth's (sigma from the law's b_sigma, at least 2 % of the truth's slope for the parameters'
// own scatter). Prints per case each hidden effect and what came back, then the fraction.
// Run it isolated: scripts/isolated.sh build/bin/fralab-bench-envelope --cases 20
#include <sys/wait.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "random_plant.h"

using namespace fralab;
using namespace fralab::testing;

namespace {

constexpr double kCentre = 80;  // speed_pct where the laws take the drawn case's values

double law_at(const Json& law, double x) {
  const std::string form = law.at("form");
  const double a = law.at("a"), b = law.at("b");
  if (form == "linear") return a + b * x;
  if (form == "power") return a * std::pow(x, b);
  return a;
}

// The slope of a law over [x0, x1] and its sigma from b_sigma (-1: unknown).
std::pair<double, double> secant(const Json& law, double x0, double x1) {
  const double s = (law_at(law, x1) - law_at(law, x0)) / (x1 - x0);
  const double bs = law.contains("b_sigma") ? law.at("b_sigma").get<double>() : -1.0;
  const std::string form = law.at("form");
  if (form == "constant" || bs < 0) return {s, -1};
  if (form == "linear") return {s, bs};
  const double a = law.at("a"), b = law.at("b");  // d secant / d b for a x^b
  const double d =
      (a * std::pow(x1, b) * std::log(x1) - a * std::pow(x0, b) * std::log(x0)) / (x1 - x0);
  return {s, std::abs(d) * bs};
}

// A case's operating points and hidden laws: points x in [60, 100] (3-5 of them), per hidden
// effect with a parameter an exponent p (value (x / kCentre)^p), per path a gain exponent q.
struct Laws {
  std::vector<double> xs;
  std::vector<HiddenEffect> laws;
  std::vector<double> p, q;
};

Laws draw_laws(const RandomCase& c, uint64_t seed, int i) {
  Laws L;
  std::mt19937_64 g(seed * 6700417u + uint64_t(i));
  std::uniform_real_distribution<double> u(0, 1);
  const int n_points = 3 + int(g() % 3);
  for (int k = 0; k < n_points; ++k) L.xs.push_back(60 + 40.0 * k / (n_points - 1));
  for (const HiddenEffect& e : c.hidden) {
    Model probe = c.engine;
    if (!set_hidden_parameter(probe, e, e.value)) continue;  // no parameter to schedule
    L.laws.push_back(e);
    L.p.push_back((u(g) < 0.5 ? -1 : 1) * (0.5 + u(g)));
  }
  for (size_t k = 0; k < c.simulation.paths.size(); ++k) L.q.push_back(u(g) - 0.5);
  return L;
}

// The engine and the simulation at each point, DIR/engines/xNN.json and DIR/simulations/xNN.json.
void write_points(const RandomCase& c, const Laws& L, const std::string& dir) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir + "/engines");
  std::filesystem::create_directories(dir + "/simulations");
  for (double x : L.xs) {
    Model eng = c.engine, sim = c.simulation;
    for (size_t k = 0; k < L.laws.size(); ++k)
      set_hidden_parameter(eng, L.laws[k], L.laws[k].value * std::pow(x / kCentre, L.p[k]));
    for (Model* m : {&eng, &sim}) {
      m->speed_pct = x;
      for (ModelPath& path : m->paths)
        for (size_t k = 0; k < c.simulation.paths.size(); ++k)
          if (c.simulation.paths[k].input == path.input &&
              c.simulation.paths[k].output == path.output)
            path.tf.gain *= std::pow(x / kCentre, L.q[k]);
    }
    const std::string name = "x" + std::to_string(int(std::lround(x))) + ".json";
    save_model(dir + "/engines/" + name, eng);
    save_model(dir + "/simulations/" + name, sim);
  }
}

// The hidden laws envelope.json recovers (its finding's secant over the points within 2 sigma or
// 2 %), each said on a line.
int recovered_laws(const Json& env, const Laws& L) {
  int recovered = 0;
  for (size_t k = 0; k < L.laws.size(); ++k) {
    const HiddenEffect& e = L.laws[k];
    const double x0 = L.xs.front(), x1 = L.xs.back();
    const double truth =
        e.value * (std::pow(x1 / kCentre, L.p[k]) - std::pow(x0 / kCentre, L.p[k])) / (x1 - x0);
    std::string got = "not found";
    bool ok = false;
    for (const Json& f : env.at("findings")) {
      if (f.at("cause") != to_string(e.cause) || f.at("scope") != to_string(e.scope) ||
          f.at("input").get<std::string>() != e.input ||
          f.at("output").get<std::string>() != e.output || !e.param ||
          f.at("parameter") != to_string(*e.param))
        continue;
      const auto [s, sigma] = secant(f.at("law"), x0, x1);
      const double tol = 2 * std::max(sigma, 0.02 * std::abs(truth));
      ok = sigma >= 0 && std::abs(s - truth) <= tol;
      got = std::string(f.at("law").at("form")) + " law, slope " + std::to_string(s) + " +- " +
            std::to_string(sigma) + " at " + std::to_string(f.at("values").size()) + " points";
      break;
    }
    recovered += ok;
    std::printf("    %s: %s, slope %g (exponent %.2f); %s: %s\n", e.describe().c_str(),
                e.param ? to_string(*e.param) : "", truth, L.p[k], got.c_str(),
                ok ? "recovered" : "MISSED");
  }
  return recovered;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-bench-envelope: laws across operating points recovered on random plants"};
  int cases = 20, first = 0;
  uint64_t seed = 1;
  std::string out = "out/envelope-selfcheck", band = "0.1:20", excitation = "auto";
  int ppd = 5;
  double min_recovered = 0;
  app.add_option("--cases", cases)->capture_default_str();
  app.add_option("--first", first, "index of the first case")->capture_default_str();
  app.add_option("--seed", seed, "generator seed")->capture_default_str();
  app.add_option("--out", out)->capture_default_str();
  app.add_option("--band", band, "measure band, Hz")->capture_default_str();
  app.add_option("--points-per-decade", ppd)->capture_default_str();
  app.add_option("--excitation", excitation)->capture_default_str();
  app.add_option("--min-recovered", min_recovered, "exit 1 below this fraction");
  CLI11_PARSE(app, argc, argv);
  const std::string bin =
      std::filesystem::canonical("/proc/self/exe").parent_path().string() + "/fralab";
  int hidden = 0, recovered = 0, failed = 0;
  for (int i = first; i < first + cases; ++i) {
    const RandomCase c = random_case(seed, i, 1 + i % 2);
    const Laws L = draw_laws(c, seed, i);
    const std::vector<double>& xs = L.xs;
    const int n_points = int(xs.size());
    const std::string dir = out + "/" + c.name;
    write_points(c, L, dir);
    const std::string cmd = bin + " envelope --engine " + dir + "/engines --simulation " + dir +
                            "/simulations --out " + dir + "/envelope --no-plots --band " + band +
                            " --points-per-decade " + std::to_string(ppd) + " --excitation " +
                            excitation + " --seed 5 > " + dir + "/log.txt 2>&1";
    const int st = std::system(cmd.c_str());
    const int status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    hidden += int(L.laws.size());
    if (status != 0) {
      ++failed;
      std::printf("%s: fralab envelope failed (status %d; see %s/log.txt)\n", c.name.c_str(),
                  status, dir.c_str());
      continue;
    }
    const Json env = json_load_file(dir + "/envelope/envelope.json");
    std::printf("%s: %zu inputs x %zu outputs, %d points\n", c.name.c_str(),
                c.simulation.inputs.size(), c.simulation.outputs.size(), n_points);
    recovered += recovered_laws(env, L);
    std::fflush(stdout);
  }
  const double fraction = hidden ? double(recovered) / hidden : 1.0;
  std::printf(
      "envelope selfcheck: %d cases (seed %llu, band %s Hz, %d/decade, %s): %d of %d hidden laws "
      "recovered (%.3f), %d envelopes failed\n",
      cases, (unsigned long long)seed, band.c_str(), ppd, excitation.c_str(), recovered, hidden,
      fraction, failed);
  return fraction >= min_recovered ? 0 : 1;
}
