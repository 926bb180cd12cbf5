// The identifier on randomised frequency responses it has never seen (tests/util/
// random_frd.h: orders 1-8 with 0..n zeros, close light resonances, right-half-plane zeros, poles
// over four decades, a pole outside the band, sparse grids, delays), at six noise conditions
// relative to |G| and two of additive noise (0.5 % of the peak |G|, with sigma and without:
// without, the oracle is told the sigma and the orders are also compared with fralab's fit given
// it), against an oracle told the true orders and delay (refine_tf from the truth: weighted
// Levenberg-Marquardt on the same data). Prints per condition: model error rms |G_fit - G_true| /
// |G_true| over the band (median / p90, fralab and oracle), both orders right, search losses (wrong
// orders whose truth the criterion prefers: the search missed it; the other wrong orders are ones
// the data do not support), in-band roots within 2 % (fralab / oracle), 3-sigma coverage (in-band
// roots within max(2 %, 3 of their own sigma)) over all cases and over the right-order ones, the
// right-order ones' 2-sigma coverage (in-band roots within 2 of their sigma, no floor; with noise),
// median and p90 milliseconds per fit (delay auto). Then Google Benchmark timings. --verbose: a
// line per case, with both criteria.
//   ./build/bin/fralab-bench-identify-random [--cases N] [--seed S] [--verbose] [benchmark flags]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "fralab/identify/tfns.h"
#include "random_frd.h"

using namespace fralab;
using fralab::testing::model_error;
using fralab::testing::random_frd_case;
using fralab::testing::RandomFrdCase;

namespace {

using fralab::testing::NoiseKind;

struct Condition {
  double noise;
  bool sigma;
  NoiseKind kind = NoiseKind::kRelative;
};
// The last two: additive noise (0.5 % of the peak |G| at every point, a measured path's output
// noise), with sigma and without.
const Condition kConditions[] = {{0.0, false},
                                 {0.005, true},
                                 {0.02, true},
                                 {0.05, true},
                                 {0.10, true},
                                 {0.02, false},
                                 {0.005, true, NoiseKind::kAdditive},
                                 {0.005, false, NoiseKind::kAdditive}};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * (v.size() - 1) + 0.5))];
}

// Counts in-band true roots; *within: nearest fitted root within 2 %; *covered: within
// max(2 %, 3 sigma) of that root's own sigma.
void root_counts(const std::vector<Root>& truth, const std::vector<Root>& fit,
                 const std::vector<RootInfo>& info, double lo, double hi, int* total, int* within,
                 int* covered, int* covered2 = nullptr) {
  for (const Root& t : truth) {
    const double wt = t.pair ? t.wn : std::abs(t.real);
    if (wt < lo || wt > hi) continue;
    std::complex<double> lt = t.locations()[0];
    if (lt.imag() < 0) lt = std::conj(lt);
    double best = INFINITY, sig = 0;
    for (size_t k = 0; k < fit.size(); ++k) {
      std::complex<double> lf = fit[k].locations()[0];
      if (lf.imag() < 0) lf = std::conj(lf);
      const double e = std::abs(lf - lt) / std::abs(lt);
      if (e < best) best = e, sig = k < info.size() ? std::max(0.0, info[k].rel_sigma) : 0.0;
    }
    ++*total;
    *within += best < 0.02;
    *covered += best < std::max(0.02, 3 * sig);
    if (covered2) *covered2 += best < 2 * sig;
  }
}

// A wrong order counts as a search loss when the truth's structure, refined on the same data, has
// a criterion lower than the fit's by more than this (chi^2 units).
constexpr double kLossMargin = 1.0;

FitOptions oracle_options(const RandomFrdCase& c) {
  FitOptions o;
  o.delay = FitOptions::Delay::kFixed;
  o.delay_s = c.truth.delay_s;
  return o;
}

}  // namespace

// One noise condition's tally over its cases: the errors of fralab's fit and of the oracle, the
// orders, roots and intervals, and the fit times; one table row.
struct ConditionTally {
  std::vector<double> ef, eo, ms, es;  // es: the fits with sigma (additive, no sigma)
  int right = 0, tot = 0, within = 0, covered = 0, tot_o = 0, within_o = 0, covered_o = 0;
  int losses = 0, as_sigma = 0;
  int tot_r = 0, covered_r = 0, covered2_r = 0;  // in the cases whose orders are right

  // Case i of condition k (seed): fitted, scored, and with `verbose` described on a line.
  void add(const Condition& k, int i, uint64_t seed, bool verbose) {
    const bool additive = k.kind == NoiseKind::kAdditive;
    const RandomFrdCase c = random_frd_case(i, k.noise, k.sigma, seed, k.kind);
    const auto t0 = std::chrono::steady_clock::now();
    const FitResult r = fit_tf(c.points, FitOptions{});
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    // Additive noise without sigma: the oracle is told the noise too (its weights 1 / sigma^2,
    // the same draw with sigma), and fralab's fit with that sigma is the orders' reference.
    const RandomFrdCase cs =
        additive && !k.sigma && k.noise > 0 ? random_frd_case(i, k.noise, true, seed, k.kind) : c;
    const FitResult o = refine_tf(cs.points, c.truth, oracle_options(c));
    FitResult rs;  // additive without sigma: the fit with the sigma withheld
    if (additive && !k.sigma && k.noise > 0) {
      rs = fit_tf(cs.points, FitOptions{});
      as_sigma += rs.num_order == r.num_order && rs.den_order == r.den_order;
      es.push_back(model_error(rs.tf, c.truth, c.w_lo, c.w_hi));
    }
    ef.push_back(model_error(r.tf, c.truth, c.w_lo, c.w_hi));
    eo.push_back(model_error(o.tf, c.truth, c.w_lo, c.w_hi));
    const bool ok = r.num_order == c.truth.num_order() && r.den_order == c.truth.den_order();
    right += ok;
    root_counts(c.truth.poles, r.tf.poles, r.pole_info, c.w_lo, c.w_hi, &tot, &within, &covered);
    root_counts(c.truth.zeros, r.tf.zeros, r.zero_info, c.w_lo, c.w_hi, &tot, &within, &covered);
    if (ok) {  // the right-order cases' coverage: the sigmas' honesty apart from missed roots
      int w2 = 0;
      root_counts(c.truth.poles, r.tf.poles, r.pole_info, c.w_lo, c.w_hi, &tot_r, &w2, &covered_r,
                  &covered2_r);
      root_counts(c.truth.zeros, r.tf.zeros, r.zero_info, c.w_lo, c.w_hi, &tot_r, &w2, &covered_r,
                  &covered2_r);
    }
    root_counts(c.truth.poles, o.tf.poles, o.pole_info, c.w_lo, c.w_hi, &tot_o, &within_o,
                &covered_o);
    root_counts(c.truth.zeros, o.tf.zeros, o.zero_info, c.w_lo, c.w_hi, &tot_o, &within_o,
                &covered_o);
    // The order criterion fit_tf compares adequate candidates by (chi^2 + ln(2N) p), for the
    // fit and for the truth's structure refined with its delay free (when it has one): a wrong
    // order whose truth has a criterion lower by kLossMargin is a search the fit lost; higher,
    // the data do not support the true order. (With sigma only: without, the oracle has no
    // chi^2.)
    double crit_fit = NAN, crit_truth = NAN;
    if (k.sigma && (!ok || verbose)) {
      FitOptions ao;
      ao.delay = c.truth.delay_s > 0 ? FitOptions::Delay::kAuto : FitOptions::Delay::kNone;
      const FitResult oa = refine_tf(c.points, c.truth, ao);
      auto crit = [&](const FitResult& f, bool free_delay) {
        const double n = double(f.n_points), p = f.num_order + f.den_order + 1 + free_delay;
        return f.chi2_per_dof * std::max(1.0, n - p / 2) + std::log(2 * n) * p;
      };
      crit_fit = crit(r, r.tf.delay_s > 0);
      crit_truth = crit(oa, c.truth.delay_s > 0);
      losses += !ok && crit_truth < crit_fit - kLossMargin;
    }
    if (verbose)
      std::printf(
          "  %2d %-20s N=%2zu truth %d/%d tau %.3f | fit %d/%d tau %.4f %-18s err %.2e oracle "
          "%.2e %.1f ms chi2 %.3f oracle %.3f crit %.1f truth %.1f noise %.3g / %.3g%s\n",
          i, c.category.c_str(), c.points.size(), c.truth.num_order(), c.truth.den_order(),
          c.truth.delay_s, r.num_order, r.den_order, r.tf.delay_s, r.status_str().c_str(),
          ef.back(), eo.back(), ms.back(), r.chi2_per_dof, o.chi2_per_dof, crit_fit, crit_truth,
          r.noise_rel, r.noise_abs, ok ? "" : "  WRONG");
    if (verbose && !es.empty())
      std::printf("       with sigma %d/%d err %.2e%s\n", rs.num_order, rs.den_order, es.back(),
                  rs.num_order == r.num_order && rs.den_order == r.den_order ? "" : "  DIFFERS");
  }

  // The condition's row of the table over its n_cases cases.
  void print_row(const Condition& k, int n_cases) const {
    const bool additive = k.kind == NoiseKind::kAdditive;
    const double mf = quantile(ef, 0.5), pf = quantile(ef, 0.9), mo = quantile(eo, 0.5),
                 po = quantile(eo, 0.9);
    char as[64] = "";
    if (additive && !k.sigma)
      std::snprintf(as, sizeof as, " (%.0f %%; error %.2f / %.2f of it)",
                    100.0 * as_sigma / n_cases, mf / quantile(es, 0.5), pf / quantile(es, 0.9));
    std::printf(
        "| %.1f %%%s | %s | %.2g / %.2g | %.2g / %.2g | %.2f / %.2f | %.0f %%%s | %s | %d / %d of "
        "%d (%.0f %%) | %.0f %% (oracle %.0f %%) | %.0f %% | %s | %.1f / %.1f |\n",
        100 * k.noise, additive ? " of the peak, additive" : "", k.sigma ? "yes" : "no", mf, pf, mo,
        po, mf / mo, pf / po, 100.0 * right / n_cases, as,
        k.sigma ? std::to_string(losses).c_str() : "-", within, within_o, tot,
        100.0 * within / std::max(1, within_o), 100.0 * covered / std::max(1, tot),
        100.0 * covered_o / std::max(1, tot_o), 100.0 * covered_r / std::max(1, tot_r),
        k.noise > 0
            ? (std::to_string(int(std::lround(100.0 * covered2_r / std::max(1, tot_r)))) + " %")
                  .c_str()
            : "-",
        quantile(ms, 0.5), quantile(ms, 0.9));
    std::fflush(stdout);
  }
};

static void BM_RandomCaseFits(benchmark::State& state) {
  std::vector<RandomFrdCase> cases;
  for (int i = 0; i < 32; ++i) cases.push_back(random_frd_case(i, 0.02, true, 1));
  for (auto _ : state)
    for (const auto& c : cases) benchmark::DoNotOptimize(fit_tf(c.points, FitOptions{}).tf.gain);
  state.counters["fits"] = double(cases.size());
}
BENCHMARK(BM_RandomCaseFits)->Unit(benchmark::kMillisecond);

int main(int argc, char** argv) {
  int n_cases = 32;
  uint64_t seed = 1;
  bool verbose = false;
  std::vector<char*> rest{argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--cases") && i + 1 < argc) {
      n_cases = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) {
      seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (!std::strcmp(argv[i], "--verbose")) {
      verbose = true;
    } else {
      rest.push_back(argv[i]);
    }
  }
  std::printf(
      "| noise | sigma | fralab median / p90 | oracle median / p90 | ratio median / p90 | orders "
      "right (as with sigma) | search losses | roots within 2 %% (fralab / oracle) | 3-sigma "
      "coverage | coverage, orders right | 2-sigma coverage, orders right | ms per fit median / "
      "p90 |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Condition& k : kConditions) {
    ConditionTally t;
    for (int i = 0; i < n_cases; ++i) t.add(k, i, seed, verbose);
    t.print_row(k, n_cases);
  }
  int bargc = int(rest.size());
  benchmark::Initialize(&bargc, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
