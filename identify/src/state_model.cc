#include "fralab/identify/state_model.h"

#include <cmath>
#include <functional>

#include "fralab/core/numerics.h"

namespace fralab {
namespace {

using Cx = std::complex<double>;

Cx location(const Root& r) {
  Cx l = r.locations()[0];
  return l.imag() < 0 ? std::conj(l) : l;
}

double error_of(const std::vector<FrdPoint>& pts, const std::function<Cx(double)>& g) {
  std::vector<Cx> model, meas;
  for (const auto& p : pts) {
    if (!p.valid || p.mag <= 0) continue;
    model.push_back(g(p.w));
    meas.push_back(p.value());
  }
  return detail::rms_log_error(model, meas);
}

}  // namespace

Cx StateModel::at(int o, int i, double w) const {
  const int n = order;
  Eigen::MatrixXcd M = Cx(0, w) * Eigen::MatrixXcd::Identity(n, n) - A.cast<Cx>();
  Cx g = D(o, i);
  if (n > 0) {
    Eigen::VectorXcd x = M.partialPivLu().solve(B.col(i).cast<Cx>());
    g += (this->C.row(o).cast<Cx>() * x)(0);
  }
  return g * std::polar(1.0, -w * delay_s(o, i));
}

StateModel build_state_model(const TransferMatrix& m,
                             const std::map<std::string, std::vector<FrdPoint>>& data) {
  StateModel s;
  s.inputs = m.inputs;
  s.outputs = m.outputs;
  const int no = int(m.outputs.size()), ni = int(m.inputs.size()), nk = int(m.clusters.size());
  s.delay_s = Eigen::MatrixXd::Zero(no, ni);
  s.D = Eigen::MatrixXd::Zero(no, ni);
  std::vector<Eigen::MatrixXcd> R(nk, Eigen::MatrixXcd::Zero(no, ni));  // residues per cluster
  for (int o = 0; o < no; ++o) {
    for (int i = 0; i < ni; ++i) {
      auto it = m.fits.find({m.outputs[o], m.inputs[i]});
      const std::string key = m.inputs[i] + ":" + m.outputs[o];
      auto dit = data.find(key);
      if (it == m.fits.end() || it->second.status != FitResult::Status::kConverged ||
          dit == data.end())
        continue;
      const Tf& tf = it->second.tf;
      s.delay_s(o, i) = tf.delay_s;
      // The clusters of this path's poles.
      std::vector<int> ks;
      for (const Root& p : tf.poles) {
        int best = -1;
        double bd = INFINITY;
        for (int k = 0; k < nk; ++k) {
          if (m.clusters[k].mean.pair != p.pair) continue;
          double d = std::abs(location(m.clusters[k].mean) - location(p));
          if (d < bd) bd = d, best = k;
        }
        if (best >= 0 && std::find(ks.begin(), ks.end(), best) == ks.end()) ks.push_back(best);
      }
      // Unknowns: d (when the fit is biproper), a real residue per real pole, Re/Im per pair.
      const bool has_d = tf.num_order() >= tf.den_order();
      int nu = has_d ? 1 : 0;
      for (int k : ks) nu += m.clusters[k].mean.pair ? 2 : 1;
      std::vector<FrdPoint> pts;
      for (const auto& p : dit->second)
        if (p.valid && p.mag > 0) pts.push_back(p);
      if (pts.empty() || nu == 0) continue;
      Eigen::MatrixXd A(2 * pts.size(), nu);
      Eigen::VectorXd b(2 * pts.size());
      for (size_t q = 0; q < pts.size(); ++q) {
        const double w = pts[q].w;
        const double wt = pts[q].sigma > 0 ? 1.0 / pts[q].sigma : 1.0 / pts[q].mag;
        const Cx sj(0, w);
        const Cx g = pts[q].value() * std::polar(1.0, w * tf.delay_s);  // delay removed
        int c = 0;
        auto put = [&](Cx v) {
          A(q, c) = wt * v.real();
          A(pts.size() + q, c) = wt * v.imag();
          ++c;
        };
        if (has_d) put(1.0);
        for (int k : ks) {
          const Cx p = location(m.clusters[k].mean);
          if (m.clusters[k].mean.pair) {  // r/(s-p) + conj(r)/(s-conj p): basis for Re r and Im r
            put(1.0 / (sj - p) + 1.0 / (sj - std::conj(p)));
            put(Cx(0, 1) / (sj - p) - Cx(0, 1) / (sj - std::conj(p)));
          } else {
            put(1.0 / (sj - p.real()));
          }
        }
        b(q) = wt * g.real();
        b(pts.size() + q) = wt * g.imag();
      }
      Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
      int c = 0;
      if (has_d) s.D(o, i) = x(c++);
      for (int k : ks) {
        if (m.clusters[k].mean.pair) {
          R[k](o, i) = Cx(x(c), x(c + 1));
          c += 2;
        } else {
          R[k](o, i) = x(c++);
        }
      }
    }
  }
  // Rank-one residue matrices -> states.
  for (int k = 0; k < nk; ++k) s.order += m.clusters[k].mean.order();
  s.A = Eigen::MatrixXd::Zero(s.order, s.order);
  s.B = Eigen::MatrixXd::Zero(s.order, ni);
  s.C = Eigen::MatrixXd::Zero(no, s.order);
  int x0 = 0;
  for (int k = 0; k < nk; ++k) {
    const Cx p = location(m.clusters[k].mean);
    Eigen::JacobiSVD<Eigen::MatrixXcd> svd(R[k], Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto sv = svd.singularValues();
    const double total = sv.squaredNorm();
    s.rank1_loss.push_back(total > 0 ? 1.0 - sv(0) * sv(0) / total : 0.0);
    const Eigen::VectorXcd c = svd.matrixU().col(0) * std::sqrt(sv(0));
    const Eigen::VectorXcd bb = svd.matrixV().col(0).conjugate() * std::sqrt(sv(0));  // R ~ c b^T
    if (!m.clusters[k].mean.pair) {
      // A real pole's residues are real: take the real rank-one factors.
      Eigen::JacobiSVD<Eigen::MatrixXd> rs(R[k].real(), Eigen::ComputeThinU | Eigen::ComputeThinV);
      const double s1 = rs.singularValues()(0);
      s.A(x0, x0) = p.real();
      s.B.row(x0) = (rs.matrixV().col(0) * std::sqrt(s1)).transpose();
      s.C.col(x0) = rs.matrixU().col(0) * std::sqrt(s1);
      x0 += 1;
    } else {
      // z' = p z + b^T u, y = 2 Re(c z): with z = x1 + j x2, x' = [[s, -w], [w, s]] x + [Re b; Im
      // b] u, y = 2 (Re c) x1 - 2 (Im c) x2.
      s.A(x0, x0) = p.real();
      s.A(x0, x0 + 1) = -p.imag();
      s.A(x0 + 1, x0) = p.imag();
      s.A(x0 + 1, x0 + 1) = p.real();
      s.B.row(x0) = bb.real().transpose();
      s.B.row(x0 + 1) = bb.imag().transpose();
      s.C.col(x0) = 2 * c.real();
      s.C.col(x0 + 1) = -2 * c.imag();
      x0 += 2;
    }
  }
  // Check against the data.
  double sum = 0;
  int n = 0;
  for (int o = 0; o < no; ++o) {
    for (int i = 0; i < ni; ++i) {
      const std::string key = m.inputs[i] + ":" + m.outputs[o];
      auto dit = data.find(key);
      if (dit == data.end() || !m.fits.count({m.outputs[o], m.inputs[i]})) continue;
      const double e = error_of(dit->second, [&](double w) { return s.at(o, i, w); });
      s.path_error[key] = e;
      sum += e * e;
      ++n;
    }
  }
  s.error = n ? std::sqrt(sum / n) : 0.0;
  return s;
}

Json state_model_json(const StateModel& s) {
  auto mat = [](const Eigen::MatrixXd& M) {
    Json a = Json::array();
    for (int r = 0; r < M.rows(); ++r) {
      Json row = Json::array();
      for (int c = 0; c < M.cols(); ++c) row.push_back(M(r, c));
      a.push_back(row);
    }
    return a;
  };
  return Json{{"order", s.order},
              {"inputs", s.inputs},
              {"outputs", s.outputs},
              {"A", mat(s.A)},
              {"B", mat(s.B)},
              {"C", mat(s.C)},
              {"D", mat(s.D)},
              {"delay_s", mat(s.delay_s)},
              {"path_error", s.path_error},
              {"error", s.error},
              {"rank1_loss", s.rank1_loss},
              {"metric", "rms over points of |ln(G_model/G_measured)|"}};
}

}  // namespace fralab
