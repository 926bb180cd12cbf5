#include "random_modal.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "exact_measurement.h"
#include "fralab/identify/pole_set_fit.h"

namespace fralab::testing {

namespace {

using C = std::complex<double>;

struct Structure {
  std::vector<double> wn, zeta;
  std::vector<std::vector<double>> out_shape, in_shape;  // [output][mode], [input][mode]
};

// The model of a structure: path o <- i is sum_k A / (wn^2 - w^2 + 2 j zeta wn w), A the shapes'
// product times the unchanged structure's wn_k^2 (`base`: a changed structure keeps its shapes),
// written as a factored tf.
Model model_of(const Structure& s, const Structure& base, const std::vector<std::string>& ins,
               const std::vector<std::string>& outs, const std::string& name) {
  Model m;
  m.name = name;
  m.source = name;
  for (const std::string& n : ins) {
    ModelInput in;
    in.name = n;
    in.units = "1";
    in.full_scale = 10;
    m.inputs.push_back(in);
  }
  for (const std::string& n : outs) {
    ModelOutput o;
    o.name = n;
    o.units = "1";
    m.outputs.push_back(o);
  }
  for (size_t o = 0; o < outs.size(); ++o) {
    for (size_t i = 0; i < ins.size(); ++i) {
      PoleSetFit f;
      std::vector<C> r;
      for (size_t k = 0; k < s.wn.size(); ++k) {
        const double wd = s.wn[k] * std::sqrt(1 - s.zeta[k] * s.zeta[k]);
        f.poles.push_back(C(-s.zeta[k] * s.wn[k], wd));
        const double A = s.out_shape[o][k] * s.in_shape[i][k] * base.wn[k] * base.wn[k];
        r.push_back(A / C(0, 2 * wd));  // the residue at p of A / ((s - p)(s - conj p))
      }
      f.residues.push_back(r);
      f.d.push_back(0.0);
      m.paths.push_back({outs[o], ins[i], f.to_tf(0), Json::object()});
    }
  }
  return m;
}

}  // namespace

RandomCase random_modal_case(uint64_t seed, int index, int n_hidden) {
  std::mt19937_64 g(seed * 2654435761u + uint64_t(index) * 40503u + 11u);
  std::uniform_real_distribution<double> u(0, 1);
  auto logu = [&](double lo, double hi) { return lo * std::pow(hi / lo, u(g)); };
  auto sign = [&] { return u(g) < 0.4 ? -1.0 : 1.0; };
  const int nm = 2 + int(g() % 7), ni = 1 + int(g() % 3), no = 2 + int(g() % 4);
  Structure s;
  while (int(s.wn.size()) < nm) {
    const double w = logu(2, 50);
    if (std::all_of(s.wn.begin(), s.wn.end(), [&](double x) { return std::abs(w / x - 1) > 0.04; }))
      s.wn.push_back(w);
  }
  std::sort(s.wn.begin(), s.wn.end());
  for (int k = 0; k < nm; ++k) s.zeta.push_back(logu(0.01, 0.05));
  s.out_shape.assign(size_t(no), std::vector<double>(size_t(nm)));
  s.in_shape.assign(size_t(ni), std::vector<double>(size_t(nm)));
  for (auto& row : s.out_shape)
    for (double& x : row) x = sign() * logu(0.1, 1);
  for (auto& row : s.in_shape)
    for (double& x : row) x = sign() * logu(0.1, 1);
  std::vector<std::string> ins, outs;
  for (int i = 0; i < ni; ++i) ins.push_back("F" + std::to_string(i));
  for (int o = 0; o < no; ++o) outs.push_back("A" + std::to_string(o));
  RandomCase c;
  c.name = "modal" + std::to_string(index);
  c.simulation = model_of(s, s, ins, outs, "random structure " + std::to_string(index));
  Structure e = s;
  const int nh = n_hidden >= 0 ? n_hidden : int(g() % 4);
  std::vector<int> moved;
  std::vector<std::pair<std::string, double>> calibrations;
  for (int h = 0; h < nh; ++h) {
    const int kind = int(g() % 4);
    if (kind == 3 && ni > 1) {  // an output's calibration
      const std::string out = outs[g() % size_t(no)];
      if (std::any_of(calibrations.begin(), calibrations.end(),
                      [&](const auto& x) { return x.first == out; }))
        continue;
      const double db = sign() * logu(1.5, 4);
      calibrations.push_back({out, db});
      HiddenEffect cal;
      cal.cause = CauseKind::kGainMismatch, cal.scope = Scope::kOutput, cal.output = out;
      cal.param = Param::kGainDb, cal.value = db, cal.tol_abs = 0.3;
      c.hidden.push_back(cal);
      continue;
    }
    const int k = int(g() % size_t(nm));
    if (std::find(moved.begin(), moved.end(), k) != moved.end()) continue;
    moved.push_back(k);
    HiddenEffect he;
    he.cause = CauseKind::kPoleShift, he.scope = Scope::kPlant;
    he.at[Param::kFromRadS] = s.wn[size_t(k)];  // the simulated mode it moves
    if (kind != 1) {                            // the frequency (and, kind 2, the damping too)
      e.wn[size_t(k)] *= 1 + sign() * logu(0.01, 0.05);
      he.param = Param::kToRadS, he.value = e.wn[size_t(k)], he.tol_rel = 0.003;
    }
    if (kind >= 1) {  // the damping (kind 1 alone: a damping_error of the plant's)
      e.zeta[size_t(k)] *= u(g) < 0.3 ? 0.5 : logu(1.5, 3);
      if (kind == 1)
        he.cause = CauseKind::kDampingError, he.param = Param::kToZeta,
        he.value = e.zeta[size_t(k)], he.tol_rel = 0.15,
        he.at = {{Param::kWnRadS, s.wn[size_t(k)]}};
    }
    c.hidden.push_back(he);
  }
  c.engine = model_of(e, s, ins, outs, "random structure " + std::to_string(index) + ", changed");
  for (const auto& [out, db] : calibrations) {
    ModelOutput& o = c.engine.outputs[size_t(c.engine.output_index(out))];
    o.sensor = Tf{};
    o.sensor->gain = std::pow(10.0, db / 20);
  }
  return c;
}

void set_lab_noise(RandomCase& c, double rel) {
  for (ModelOutput& out : c.engine.outputs) {
    double strongest = 0;
    for (const ModelPath& p : c.engine.paths) {
      if (p.output != out.name) continue;
      const double amplitude =
          0.02 * c.engine.inputs[size_t(c.engine.input_index(p.input))].full_scale;
      for (const Root& r : p.tf.poles)
        if (r.pair) strongest = std::max(strongest, std::abs(p.tf.at(r.wn)) * amplitude);
    }
    out.noise_rms = rel * strongest;
  }
}

std::vector<MeasuredPair> modal_measurement(const RandomCase& c, uint64_t seed, double rel_sigma) {
  double lo = INFINITY, hi = 0, zmin = 1;
  for (const ModelPath& p : c.engine.paths)
    for (const Root& r : p.tf.poles)
      if (r.pair) lo = std::min(lo, r.wn), hi = std::max(hi, r.wn), zmin = std::min(zmin, r.zeta);
  lo /= 1.3, hi *= 1.3;
  const double ratio = 1 + zmin / 2;  // four lines in the half-power band 2 zeta wn
  const int n = int(std::ceil(std::log(hi / lo) / std::log(ratio))) + 1;
  std::vector<double> w;
  for (int j = 0; j < n; ++j) w.push_back(lo * std::pow(ratio, j));
  return exact_measurement(c.engine, w, seed, rel_sigma);
}

}  // namespace fralab::testing
