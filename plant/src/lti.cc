#include "fralab/plant/lti.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <unsupported/Eigen/MatrixFunctions>

namespace fralab {
namespace {

using C = std::complex<double>;

// phi1(x) = (e^x - 1)/x and phi2(x) = (e^x - 1 - x)/x^2, accurate for small |x|.
C phi1(C x) {
  if (std::abs(x) < 1e-4) return 1.0 + x / 2.0 + x * x / 6.0 + x * x * x / 24.0;
  return (std::exp(x) - 1.0) / x;
}
C phi2(C x) {
  if (std::abs(x) < 1e-2) {
    C term = 0.5, sum = 0.0;
    for (int k = 0; k < 8; ++k) {  // sum x^k / (k+2)!
      sum += term;
      term *= x / double(k + 3);
    }
    return sum;
  }
  return (std::exp(x) - 1.0 - x) / (x * x);
}

// a(s) b(s), both in ascending powers.
std::vector<double> poly_mul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> r(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

// A root's unity-DC-gain factor in ascending powers: 1 + 2 zeta s / wn + s^2 / wn^2, or 1 - s / r.
std::vector<double> unity_dc_factor(const Root& r) {
  if (r.pair) return std::vector<double>{1.0, 2.0 * r.zeta / r.wn, 1.0 / (r.wn * r.wn)};
  return std::vector<double>{1.0, -1.0 / r.real};
}

// A cascade's sections N_k(s) / D_k(s), unity DC gain each, ascending powers: real poles grouped
// in twos, pairs alone; zero pairs first, then real zeros, fill the sections' numerator capacity
// in order. InputError when a zero finds no room.
struct CascadeSections {
  std::vector<std::vector<double>> dens, nums;
};

CascadeSections cascade_sections(const Tf& tf) {
  CascadeSections sec;
  std::vector<std::vector<double>>& dens = sec.dens;
  std::vector<const Root*> reals;
  for (const Root& p : tf.poles) {
    if (p.pair)
      dens.push_back(unity_dc_factor(p));
    else
      reals.push_back(&p);
  }
  for (size_t i = 0; i + 1 < reals.size(); i += 2)
    dens.push_back(poly_mul(unity_dc_factor(*reals[i]), unity_dc_factor(*reals[i + 1])));
  if (reals.size() % 2) dens.push_back(unity_dc_factor(*reals.back()));
  sec.nums.assign(dens.size(), std::vector<double>{1.0});
  std::vector<int> cap(dens.size());
  for (size_t k = 0; k < dens.size(); ++k) cap[k] = static_cast<int>(dens[k].size()) - 1;
  std::vector<const Root*> zp, zr;
  for (const Root& z : tf.zeros) (z.pair ? zp : zr).push_back(&z);
  auto place = [&](const Root* z, int degree) {
    for (size_t k = 0; k < dens.size(); ++k) {
      if (cap[k] >= degree) {
        sec.nums[k] = poly_mul(sec.nums[k], unity_dc_factor(*z));
        cap[k] -= degree;
        return;
      }
    }
    throw InputError("cascade realisation: cannot place zero " + z->str());
  };
  for (const Root* z : zp) place(z, 2);
  for (const Root* z : zr) place(z, 1);
  return sec;
}

}  // namespace

std::complex<double> foh_sampled_response(const Tf& tf, double w, double fs) {
  const double h = 1.0 / fs, ws = 2 * std::numbers::pi * fs;
  std::complex<double> sum = 0.0;
  for (int m = -4000; m <= 4000; ++m) {
    const double v = w + m * ws, x = v * h / 2;
    const double f = x == 0.0 ? 1.0 : std::pow(std::sin(x) / x, 2);
    sum += tf.at(v) * f;
  }
  return sum;
}

FohLti::FohLti(const Tf& tf, double h, std::optional<Form> force) : h_(h) {
  if (!(h > 0.0)) throw InputError("FohLti: sample period must be > 0 s");
  if (!tf.proper()) {
    throw InputError("transfer function is improper (" + std::to_string(tf.num_order()) +
                     " zeros > " + std::to_string(tf.den_order()) +
                     " poles): cannot be simulated; add poles or remove zeros");
  }
  for (const Root& p : tf.poles) {
    if (!p.stable()) throw InputError("unstable pole (" + p.str() + ") cannot be simulated");
  }
  order_ = tf.den_order();
  d_ = tf.high_frequency_gain();
  // Decide the form: distinct poles -> modal.
  std::vector<C> poles;
  for (const Root& r : tf.poles) {
    auto l = r.locations();
    poles.insert(poles.end(), l.begin(), l.end());
  }
  bool distinct = true;
  for (size_t i = 0; i < poles.size(); ++i) {
    for (size_t j = i + 1; j < poles.size(); ++j) {
      double scale = std::max(std::abs(poles[i]), std::abs(poles[j]));
      if (std::abs(poles[i] - poles[j]) < 1e-3 * scale) distinct = false;
    }
  }
  form_ = force ? *force : (distinct ? Form::kModal : Form::kCascade);
  if (form_ == Form::kModal && !distinct) {
    throw InputError("modal form requested for a tf with repeated poles");
  }
  // Delay split.
  double q = tf.delay_s / h;
  m_ = static_cast<int>(std::floor(q + 1e-9));
  f_ = q - m_;
  if (f_ < 1e-9) f_ = 0.0;
  hist_.assign(m_ + 2, 0.0);
  if (form_ == Form::kModal) {
    build_modal(tf);
    md_[0] = modal_disc(h_);
    if (f_ > 0.0) {
      md_[1] = modal_disc(f_ * h_);
      md_[2] = modal_disc((1.0 - f_) * h_);
    }
  } else {
    build_cascade(tf);
    dd_[0] = dense_disc(h_);
    if (f_ > 0.0) {
      dd_[1] = dense_disc(f_ * h_);
      dd_[2] = dense_disc((1.0 - f_) * h_);
    }
  }
  reset();
}

void FohLti::build_modal(const Tf& tf) {
  // G(s) = d + sum_i c_i / (s - p_i); one mode per real pole, one per pole pair (upper half plane)
  // with weight 2 * residue, so y = d u + Re(sum c_i z_i), z_i' = p_i z_i + u.
  Tf rat = tf;
  rat.delay_s = 0.0;
  for (size_t k = 0; k < tf.poles.size(); ++k) {
    const Root& r = tf.poles[k];
    C p = r.pair ? r.locations()[0] : C(r.real, 0.0);
    if (r.pair && p.imag() < 0) p = std::conj(p);
    // Residue: (s - p) G(s) at s = p, evaluated factor by factor.
    C num(tf.gain, 0.0);
    for (const Root& z : tf.zeros) num *= z.factor(p);
    C den(1.0, 0.0);
    for (size_t j = 0; j < tf.poles.size(); ++j) {
      if (j == k) continue;
      den *= tf.poles[j].factor(p);
    }
    C own;  // factor(s) / (s - p) at s = p
    if (r.pair) {
      own = (p - std::conj(p)) / (r.wn * r.wn);
    } else {
      own = C(-1.0 / r.real, 0.0);
    }
    C res = num / (den * own);
    if (r.pair) {
      // A critically/over-damped "pair" (zeta >= 1) is two real poles.
      if (r.zeta >= 1.0) {
        C p2 = std::conj(r.locations()[1]);
        // Two distinct real poles: residues at each.
        C num2(tf.gain, 0.0);
        for (const Root& z : tf.zeros) num2 *= z.factor(p2);
        C den2(1.0, 0.0);
        for (size_t j = 0; j < tf.poles.size(); ++j) {
          if (j != k) den2 *= tf.poles[j].factor(p2);
        }
        C l1 = r.locations()[0], l2 = r.locations()[1];
        C r1 = num / (den * ((l1 - l2) / (r.wn * r.wn)));
        C r2 = num2 / (den2 * ((l2 - l1) / (r.wn * r.wn)));
        p_.push_back(l1);
        c_.push_back(r1);
        p_.push_back(l2);
        c_.push_back(r2);
        continue;
      }
      res *= 2.0;
    }
    p_.push_back(p);
    c_.push_back(res);
  }
  z_.assign(p_.size(), C(0.0, 0.0));
}

FohLti::ModalDisc FohLti::modal_disc(double h) const {
  ModalDisc d;
  for (C p : p_) {
    C x = p * h;
    d.phi.push_back(std::exp(x));
    d.g0.push_back(h * phi1(x));
    d.g1.push_back(h * phi2(x));
  }
  return d;
}

void FohLti::build_cascade(const Tf& tf) {
  const CascadeSections sec = cascade_sections(tf);
  const std::vector<std::vector<double>>&dens = sec.dens, &nums = sec.nums;
  const int n = order_;
  a_ = Eigen::MatrixXd::Zero(n, n);
  b_ = Eigen::VectorXd::Zero(n);
  cr_ = Eigen::RowVectorXd::Zero(n);
  // Series: x_k' = A_k x_k + B_k y_{k-1}; y_k = C_k x_k + D_k y_{k-1}; y_0 = u.
  // Track how y_{k-1} depends on the state (row) and on u (scalar).
  Eigen::RowVectorXd yrow = Eigen::RowVectorXd::Zero(n);
  double yu = 1.0;
  int off = 0;
  for (size_t k = 0; k < dens.size(); ++k) {
    std::vector<double> den = dens[k], num = nums[k];
    if (k == 0)
      for (double& c : num) c *= tf.gain;
    const int q = static_cast<int>(den.size()) - 1;
    num.resize(q + 1, 0.0);
    const double lead = den[q];
    for (double& c : den) c /= lead;
    for (double& c : num) c /= lead;
    // Monic D(s) = s^q + a_{q-1} s^{q-1} + ... ; N(s) = b_q s^q + ...; D_k = b_q,
    // remainder N - b_q D has degree < q: realised by C in controllable canonical form.
    const double dk = num[q];
    Eigen::MatrixXd ak = Eigen::MatrixXd::Zero(q, q);
    for (int i = 0; i + 1 < q; ++i) ak(i, i + 1) = 1.0;
    for (int i = 0; i < q; ++i) ak(q - 1, i) = -den[i];
    Eigen::RowVectorXd ck(q);
    for (int i = 0; i < q; ++i) ck(i) = num[i] - dk * den[i];
    a_.block(off, off, q, q) = ak;
    // Input of this section: y_{k-1} = yrow x + yu u.
    for (int j = 0; j < n; ++j) a_(off + q - 1, j) += yrow(j);
    b_(off + q - 1) += yu;
    Eigen::RowVectorXd newrow = dk * yrow;
    newrow.segment(off, q) += ck;
    yrow = newrow;
    yu = dk * yu;
    off += q;
  }
  cr_ = yrow;
  d_ = yu;
  x_ = Eigen::VectorXd::Zero(n);
}

FohLti::DenseDisc FohLti::dense_disc(double h) const {
  const int n = order_;
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 2, n + 2);
  m.topLeftCorner(n, n) = a_ * h;
  m.block(0, n, n, 1) = b_ * h;
  m(n, n + 1) = 1.0;
  Eigen::MatrixXd e = m.exp();
  DenseDisc d;
  d.phi = e.topLeftCorner(n, n);
  d.g0 = e.block(0, n, n, 1);
  d.g1 = e.block(0, n + 1, n, 1);
  return d;
}

void FohLti::reset() {
  std::fill(z_.begin(), z_.end(), C(0.0, 0.0));
  if (x_.size()) x_.setZero();
  std::fill(hist_.begin(), hist_.end(), 0.0);
  pos_ = 0;
  v_prev_ = 0.0;
}

void FohLti::advance(int which, double v0, double v1) {
  if (form_ == Form::kModal) {
    const ModalDisc& d = md_[which];
    const double dv = v1 - v0;
    for (size_t i = 0; i < z_.size(); ++i) z_[i] = d.phi[i] * z_[i] + d.g0[i] * v0 + d.g1[i] * dv;
  } else {
    const DenseDisc& d = dd_[which];
    x_ = d.phi * x_ + d.g0 * v0 + d.g1 * (v1 - v0);
  }
}

double FohLti::output(double v) const {
  double y = d_ * v;
  if (form_ == Form::kModal) {
    for (size_t i = 0; i < z_.size(); ++i) y += (c_[i] * z_[i]).real();
  } else {
    y += cr_.dot(x_);
  }
  return y;
}

double FohLti::step(double u) {
  const size_t n = hist_.size();
  pos_ = (pos_ + 1) % n;
  hist_[pos_] = u;
  auto past = [&](int j) { return hist_[(pos_ + n - static_cast<size_t>(j)) % n]; };
  if (f_ == 0.0) {
    const double v = past(m_);
    advance(0, v_prev_, v);
    v_prev_ = v;
    return output(v);
  }
  // v[k] = u_foh(k h - (m + f) h); knot value u[k-1-m] at (k - 1 + f) h.
  const double knot = past(m_ + 1);
  const double v = (1.0 - f_) * past(m_) + f_ * knot;
  advance(1, v_prev_, knot);
  advance(2, knot, v);
  v_prev_ = v;
  return output(v);
}

}  // namespace fralab
