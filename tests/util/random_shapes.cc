#include "random_shapes.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <sstream>

namespace fralab::testing {

namespace {

// The draw's choices: from a byte string while it lasts (a fuzzer steers the shape), then from a
// generator seeded by it.
class Choices {
 public:
  explicit Choices(uint64_t seed) : rng_(seed) {}
  Choices(const uint8_t* b, size_t n) : bytes_(b), n_(n), rng_(hash(b, n)) {}

  double uniform() {  // [0, 1)
    if (at_ + 2 <= n_) {
      const unsigned v = unsigned(bytes_[at_]) << 8 | bytes_[at_ + 1];
      at_ += 2;
      return v / 65536.0;
    }
    return std::uniform_real_distribution<double>(0, 1)(rng_);
  }
  int integer(int lo, int hi) {  // [lo, hi]
    return lo + std::min(hi - lo, int(uniform() * (hi - lo + 1)));
  }
  bool chance(double p) { return uniform() < p; }
  double log_uniform(double lo, double hi) { return lo * std::pow(hi / lo, uniform()); }
  double gauss() { return std::normal_distribution<double>(0, 1)(rng_); }

 private:
  static uint64_t hash(const uint8_t* b, size_t n) {
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    return h;
  }
  const uint8_t* bytes_ = nullptr;
  size_t n_ = 0, at_ = 0;
  std::mt19937_64 rng_;
};

Root draw_root(Choices& c) {
  if (c.chance(0.5)) return Root::Real(-c.log_uniform(0.05, 2000));
  // Light (down to zeta 1e-4) to heavy, over five decades.
  return Root::Pair(c.log_uniform(0.05, 5000),
                    c.chance(0.3) ? c.log_uniform(1e-4, 0.05) : c.uniform() * 0.95 + 0.05);
}

std::vector<double> draw_grid(Choices& c) {
  std::vector<double> w;
  const int kind = c.integer(0, 9);
  const int n = kind == 0 ? 1 : kind == 1 ? c.integer(2, 3) : c.integer(4, 60);
  const double lo = c.log_uniform(0.01, 10), hi = lo * c.log_uniform(1.001, 1e4);
  for (int k = 0; k < n; ++k)
    w.push_back(n == 1 ? lo : lo * std::pow(hi / lo, double(k) / (n - 1)));
  if (c.chance(0.15) && n > 1)  // repeated frequencies
    for (int k = 0; k < 1 + n / 4; ++k) w.push_back(w[size_t(c.integer(0, n - 1))]);
  if (c.chance(0.1)) std::reverse(w.begin(), w.end());
  return w;
}

RandomShapeSet draw(Choices& c) {
  RandomShapeSet s;
  auto dim = [&] { return c.chance(0.5) ? c.integer(1, 2) : c.integer(1, 8); };
  const int ni = dim(), no = dim();
  for (int i = 0; i < ni; ++i) s.inputs.push_back("u" + std::to_string(i));
  for (int o = 0; o < no; ++o) s.outputs.push_back("y" + std::to_string(o));
  std::vector<Root> shared;  // a rotor's mode in every path, a sensor's or actuator's roots
  for (int k = c.integer(0, 5); k > 0; --k) shared.push_back(draw_root(c));
  std::vector<double> unit(static_cast<size_t>(no));
  for (auto& u : unit) u = c.log_uniform(1e-4, 1e4);  // mixed units
  const bool sigma_everywhere = c.chance(0.6), shared_grid = c.chance(0.6);
  const std::vector<double> grid = draw_grid(c);
  const int max_order = c.integer(2, 10);
  std::ostringstream d;
  d << ni << " inputs x " << no << " outputs, " << shared.size() << " shared roots, "
    << (sigma_everywhere ? "sigma" : "sigma on some paths") << ", "
    << (shared_grid ? "one grid" : "grids per path") << ":";
  for (int o = 0; o < no; ++o) {
    for (int i = 0; i < ni; ++i) {
      const int kind = c.integer(0, 19);  // 0-2 missing, 3-4 no response, 5 failed, 6-7 max order
      if (kind <= 2) {
        d << " -";
        continue;
      }
      Tf tf;
      tf.gain = unit[size_t(o)] * c.log_uniform(1e-3, 1e3) * (c.chance(0.2) ? -1 : 1);
      for (const Root& r : shared)
        if (c.chance(0.7) && tf.den_order() + r.order() <= max_order) tf.poles.push_back(r);
      for (int k = c.integer(0, 3); k > 0; --k) {
        const Root r = draw_root(c);
        if (tf.den_order() + r.order() <= max_order) tf.poles.push_back(r);
      }
      for (int k = c.integer(0, 2); k > 0; --k) {
        Root z = draw_root(c);
        if (c.chance(0.2)) z.pair ? z.zeta = -z.zeta : z.real = -z.real;  // right-half plane
        if (tf.num_order() + z.order() <= tf.den_order() + (c.chance(0.2) ? 1 : 0))
          tf.zeros.push_back(z);
      }
      tf.delay_s = c.chance(0.3) ? c.uniform() * 0.05 : 0.0;
      const bool no_response = kind <= 4;
      const std::vector<double> w = shared_grid ? grid : draw_grid(c);
      const bool sigma = sigma_everywhere || c.chance(0.5);
      const double noise = c.chance(0.2) ? 0.0 : c.log_uniform(1e-4, 0.3);
      std::vector<FrdPoint> pts;
      const double scale = std::abs(tf.gain);
      for (double wk : w) {
        const std::complex<double> g = no_response ? 0.0 : tf.at(wk);
        const double sd = no_response ? scale * c.log_uniform(1e-3, 1) : noise * std::abs(g);
        const std::complex<double> v =
            g + sd / std::sqrt(2.0) * std::complex<double>(c.gauss(), c.gauss());
        FrdPoint p;
        p.w = wk;
        p.mag = std::abs(v);
        p.phase_deg = std::arg(v) * 180 / M_PI;
        p.sigma = sigma ? (sd > 0 ? sd : 0.0) : -1.0;
        p.valid = !c.chance(0.05);
        if (c.chance(0.02)) p.mag = 0;  // an exact zero (a dead channel's point)
        pts.push_back(p);
      }
      const std::string key = s.inputs[size_t(i)] + ":" + s.outputs[size_t(o)];
      s.data[key] = pts;
      MatrixEntry e{s.inputs[size_t(i)], s.outputs[size_t(o)], {}};
      e.fit.tf = tf;
      e.fit.n_points = int(pts.size());
      e.fit.num_order = tf.num_order();
      e.fit.den_order = tf.den_order();
      using St = FitResult::Status;
      e.fit.status = no_response ? St::kNoResponse
                     : kind == 5 ? St::kFailed
                     : kind == 6 ? St::kNotAdequate
                     : kind <= 7 ? St::kMaxOrderReached
                                 : St::kConverged;
      if (e.fit.status == St::kNoResponse) e.fit.tf = Tf{};
      s.entries.push_back(e);
      d << " " << e.fit.status_str() << "/" << pts.size() << (sigma ? "s" : "");
    }
  }
  s.description = d.str();
  return s;
}

}  // namespace

RandomShapeSet random_shape_set(uint64_t seed) {
  Choices c(seed);
  return draw(c);
}

RandomShapeSet random_shape_set_from_bytes(const uint8_t* bytes, size_t size) {
  Choices c(bytes, size);
  return draw(c);
}

}  // namespace fralab::testing
