#include "mode_residues.h"

#include <cmath>
#include <map>
#include <mutex>
#include <vector>

#include "fralab/identify/pole_set_fit.h"

namespace fralab::diag {

namespace {

using C = std::complex<double>;

constexpr double kSame = 1e-9;  // relative: a pole is the pair's, or sits on another

// The upper member (or the real location) of a root.
C location(const Root& r) {
  return r.pair ? C(-r.zeta * r.wn, r.wn * std::sqrt(std::max(0.0, 1 - r.zeta * r.zeta)))
                : C(r.real, 0);
}

// d/ds of a root's factor at its own location, the factor being (s - p)(s - conj p) / wn^2 or
// (s - r) / (-r): the part left once (s - p) is taken out.
C own_derivative(const Root& r) {
  if (!r.pair) return C(-1 / r.real, 0);
  const C p = location(r);
  return (p - std::conj(p)) / (r.wn * r.wn);
}

// The residue of t's rational part at the k-th pole's location.
std::optional<C> residue_at(const Tf& t, size_t k) {
  const C p = location(t.poles[k]);
  if (t.poles[k].pair && t.poles[k].zeta >= 1) return std::nullopt;  // two real poles
  C v = t.gain;
  for (const Root& z : t.zeros) v *= z.factor(p);
  for (size_t j = 0; j < t.poles.size(); ++j) {
    if (j == k) continue;
    const C f = t.poles[j].factor(p);
    if (std::abs(f) < kSame) return std::nullopt;  // a repeated pole
    v /= f;
  }
  return v / own_derivative(t.poles[k]);
}

std::optional<size_t> index_of(const Tf& t, const Root& pair) {
  for (size_t k = 0; k < t.poles.size(); ++k)
    if (t.poles[k].pair && std::abs(t.poles[k].wn - pair.wn) <= kSame * pair.wn &&
        std::abs(t.poles[k].zeta - pair.zeta) <= kSame * std::max(pair.zeta, 1e-12))
      return k;
  return std::nullopt;
}

}  // namespace

std::optional<C> pair_residue(const Tf& t, const Root& pair) {
  const auto k = index_of(t, pair);
  if (!k) return std::nullopt;
  return residue_at(t, *k);
}

C residue_move_factor(C R_s, const Root& from, const Root& to, C r, C s) {
  const C p = location(from), q = location(to);
  const C rq = r * (p.imag() / q.imag());  // A = 2 j Im(p) r kept
  const C delta = rq / (s - q) + std::conj(rq) / (s - std::conj(q)) - r / (s - p) -
                  std::conj(r) / (s - std::conj(p));
  return 1.0 + delta / R_s;
}

namespace {

// The tf and the move as numbers: the cache's key.
std::vector<double> key_of(const Tf& t, const Root& from, const Root& to) {
  std::vector<double> k{t.gain, t.delay_s, from.wn, from.zeta, to.wn, to.zeta};
  for (const auto* roots : {&t.zeros, &t.poles}) {
    k.push_back(double(roots->size()));
    for (const Root& r : *roots) {
      k.push_back(r.pair ? 1.0 : 0.0);
      k.push_back(r.pair ? r.wn : r.real);
      k.push_back(r.zeta);
    }
  }
  return k;
}

std::optional<Tf> compute_moved(const Tf& t, const Root& from, const Root& to);

}  // namespace

// The later stages extend the same simulation by the same findings many times over (each sizing
// or interval search varies one finding): the factored form, a generalized eigenproblem of the
// path's order, is kept for the moves already made.
std::optional<Tf> moved_keeping_residue(const Tf& t, const Root& from, const Root& to) {
  static std::mutex mutex;
  static std::map<std::vector<double>, std::optional<Tf>> cache;
  constexpr size_t kMaxCached = 4096;
  const std::vector<double> key = key_of(t, from, to);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(key); it != cache.end()) {
      std::optional<Tf> out = it->second;
      if (out) out->extra = t.extra;
      return out;
    }
  }
  std::optional<Tf> out = compute_moved(t, from, to);
  const std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() >= kMaxCached) cache.clear();
  cache.emplace(key, out);
  return out;
}

namespace {

std::optional<Tf> compute_moved(const Tf& t, const Root& from, const Root& to) {
  const auto k = index_of(t, from);
  if (!k || t.num_order() > t.den_order()) return std::nullopt;
  PoleSetFit f;
  std::vector<C> residues;
  for (size_t j = 0; j < t.poles.size(); ++j) {
    const auto r = residue_at(t, j);
    if (!r) return std::nullopt;
    f.poles.push_back(j == *k ? location(to) : location(t.poles[j]));
    const double shape = j == *k ? location(t.poles[j]).imag() / location(to).imag() : 1.0;
    residues.push_back(t.poles[j].pair ? *r * shape : C(r->real(), 0));
  }
  f.residues.push_back(residues);
  // The constant term: R(infinity), the leading coefficients' ratio when the orders are equal.
  double d = 0;
  if (t.num_order() == t.den_order()) {
    d = t.gain;
    for (const Root& z : t.zeros) d *= z.pair ? 1 / (z.wn * z.wn) : -1 / z.real;
    for (const Root& p : t.poles) d /= p.pair ? 1 / (p.wn * p.wn) : -1 / p.real;
  }
  f.d.push_back(d);
  Tf out = f.to_tf(0);
  out.delay_s = t.delay_s;
  out.extra = t.extra;
  return out;
}

}  // namespace

}  // namespace fralab::diag
