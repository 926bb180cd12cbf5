#include "fralab/identify/transfer_matrix.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "fralab/core/text.h"

namespace fralab {
namespace {

std::string num(double v) { return significant(v, 3); }

double dist(const Root& a, const Root& b) {
  auto loc = [](const Root& r) {
    auto l = r.locations()[0];
    return l.imag() < 0 ? std::conj(l) : l;
  };
  return std::abs(loc(a) - loc(b)) / std::abs(loc(b));
}

// The scope of each cluster of m over the fitted paths (input, output): "plant" when every one is
// a member, "output" / "input" when every one into one output / from one input is (two or more),
// else "path".
void assign_scopes(TransferMatrix& m,
                   const std::vector<std::pair<std::string, std::string>>& fitted) {
  std::map<std::string, std::vector<std::string>> by_out, by_in;
  std::vector<std::string> all;
  for (const auto& [in, out] : fitted) {
    const std::string name = in + ":" + out;
    by_out[out].push_back(name);
    by_in[in].push_back(name);
    all.push_back(name);
  }
  auto covers = [](const std::vector<std::string>& members, const std::vector<std::string>& need) {
    for (const auto& n : need)
      if (std::find(members.begin(), members.end(), n) == members.end()) return false;
    return need.size() >= 2;
  };
  for (auto& c : m.clusters) {
    c.scope = "path";
    if (covers(c.pairs, all)) {
      c.scope = "plant";
      continue;
    }
    for (const auto& [o, v] : by_out)
      if (covers(c.pairs, v)) c.scope = "output", c.where = o;
    if (c.scope != "path") continue;
    for (const auto& [i, v] : by_in)
      if (covers(c.pairs, v)) c.scope = "input", c.where = i;
  }
}

// The clusters' scopes (assign_scopes), the state count they make, and their order (by modulus).
void finish_clusters(TransferMatrix& m,
                     const std::vector<std::pair<std::string, std::string>>& fitted) {
  assign_scopes(m, fitted);
  m.state_count = 0;
  for (const auto& c : m.clusters) m.state_count += c.mean.order();
  std::sort(m.clusters.begin(), m.clusters.end(), [](const PoleCluster& a, const PoleCluster& b) {
    return (a.mean.pair ? a.mean.wn : -a.mean.real) < (b.mean.pair ? b.mean.wn : -b.mean.real);
  });
}

}  // namespace

std::string factor_text(const Root& r) {
  if (r.pair) return "[(s/" + num(r.wn) + ")^2 + 2(" + num(r.zeta) + ")s/" + num(r.wn) + " + 1]";
  if (r.real < 0) return "[s/" + num(-r.real) + " + 1]";
  return "[1 - s/" + num(r.real) + "]";
}

std::string tf_to_text(const Tf& tf) {
  std::string n, d;
  for (const Root& z : tf.zeros) n += factor_text(z);
  for (const Root& p : tf.poles) d += factor_text(p);
  std::string s = num(tf.gain) + (n.empty() ? "" : " " + n);
  if (!d.empty()) s += " / " + d;
  if (tf.delay_s > 0) s += " e^(-" + num(tf.delay_s) + " s)";
  return s;
}

TransferMatrix build_transfer_matrix(const std::vector<MatrixEntry>& entries, double rel_tol) {
  TransferMatrix m;
  std::set<std::string> ins, outs;
  for (const auto& e : entries) {
    if (std::find(m.inputs.begin(), m.inputs.end(), e.input) == m.inputs.end())
      m.inputs.push_back(e.input);
    if (std::find(m.outputs.begin(), m.outputs.end(), e.output) == m.outputs.end())
      m.outputs.push_back(e.output);
    m.fits[{e.output, e.input}] = e.fit;
  }
  // Cluster the poles of converged fits.
  for (const auto& e : entries) {
    if (e.fit.status != FitResult::Status::kConverged) continue;
    for (const Root& p : e.fit.tf.poles) {
      PoleCluster* best = nullptr;
      double bd = rel_tol;
      for (auto& c : m.clusters) {
        if (c.mean.pair != p.pair) continue;
        double d = dist(p, c.mean);
        if (d < bd) bd = d, best = &c;
      }
      const std::string name = e.input + ":" + e.output;
      if (!best) {
        m.clusters.push_back({p, {name}, "", ""});
        continue;
      }
      const double k = double(best->pairs.size());
      if (p.pair) {
        best->mean.wn = (best->mean.wn * k + p.wn) / (k + 1);
        best->mean.zeta = (best->mean.zeta * k + p.zeta) / (k + 1);
      } else {
        best->mean.real = (best->mean.real * k + p.real) / (k + 1);
      }
      if (std::find(best->pairs.begin(), best->pairs.end(), name) == best->pairs.end())
        best->pairs.push_back(name);
    }
  }
  std::vector<std::pair<std::string, std::string>> fitted;
  for (const auto& e : entries)
    if (e.fit.status == FitResult::Status::kConverged) fitted.push_back({e.input, e.output});
  finish_clusters(m, fitted);
  return m;
}

CommonPoleMatrix common_pole_matrix(const TransferMatrix& m,
                                    const std::map<std::string, std::vector<FrdPoint>>& data,
                                    const PoleSetFitOptions& o) {
  CommonPoleMatrix out;
  out.matrix = m;
  out.matrix.clusters.clear();
  out.matrix.from_pole_set = true;
  std::vector<std::vector<double>> w, W;
  std::vector<std::vector<std::complex<double>>> g;
  std::vector<double> rms;
  std::vector<std::pair<std::string, std::string>> fitted;
  for (const auto& [key, fit] : m.fits) {
    const auto& [output, input] = key;
    const std::string name = input + ":" + output;
    auto it = data.find(name);
    if (!fit.has_model() || it == data.end()) continue;
    std::vector<FrdPoint> pts;
    bool sigma = true;
    for (const FrdPoint& p : it->second) {
      if (!p.valid || !(p.mag > 0)) continue;
      pts.push_back(p);
      sigma = sigma && p.sigma > 0;
    }
    std::sort(pts.begin(), pts.end(),
              [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
    pts.erase(std::unique(pts.begin(), pts.end(),
                          [](const FrdPoint& a, const FrdPoint& b) { return a.w == b.w; }),
              pts.end());
    if (pts.size() < 4) continue;
    const double rel = fit.noise_rel > 0 ? fit.noise_rel : 0.01;
    std::vector<double> wc, Wc;
    std::vector<std::complex<double>> gc;
    double e = 0;
    for (const FrdPoint& p : pts) {
      wc.push_back(p.w);
      gc.push_back(p.value() * std::polar(1.0, p.w * fit.tf.delay_s));  // the fit's delay removed
      const double s = sigma ? p.sigma : rel * p.mag;
      Wc.push_back(1 / (s * s));
      e += p.mag * p.mag;
    }
    w.push_back(wc), g.push_back(gc), W.push_back(Wc);
    rms.push_back(std::sqrt(e / double(pts.size())));
    out.paths.push_back(name);
    fitted.push_back({input, output});
  }
  if (g.empty()) {
    out.fit.message = "no path with a model and its curve";
    return out;
  }
  out.fit = fit_pole_set(w, g, W, o);
  if (out.fit.status == PoleSetFit::Status::kFailed) return out;
  constexpr double kMember = 0.01;  // a pole's peak term against the path's rms |G|
  for (size_t k = 0; k < out.fit.poles.size(); ++k) {
    const std::complex<double> p = out.fit.poles[k];
    PoleCluster c;
    c.mean =
        p.imag() == 0 ? Root::Real(p.real()) : Root::Pair(std::abs(p), -p.real() / std::abs(p));
    for (size_t j = 0; j < out.paths.size(); ++j) {
      const double peak = std::abs(out.fit.residues[j][k]) / std::max(std::abs(p.real()), 1e-300);
      if (peak >= kMember * rms[j]) c.pairs.push_back(out.paths[j]);
    }
    if (c.pairs.empty()) continue;  // a pole no path needs
    out.matrix.clusters.push_back(c);
  }
  finish_clusters(out.matrix, fitted);
  return out;
}

Json transfer_matrix_json(const TransferMatrix& m) {
  Json j{{"inputs", m.inputs},
         {"outputs", m.outputs},
         {"paths", Json::array()},
         {"common_poles", Json::array()},
         {"state_count", m.state_count}};
  for (const auto& [k, f] : m.fits) {
    Json e = fit_to_json(f, k.second + ":" + k.first);
    e["output"] = k.first;
    e["input"] = k.second;
    e["text"] = tf_to_text(f.tf);
    j["paths"].push_back(e);
  }
  for (const auto& c : m.clusters) {
    j["common_poles"].push_back({{"pole", root_to_json(c.mean)},
                                 {"pairs", c.pairs},
                                 {"scope", c.scope},
                                 {"where", c.where}});
  }
  return j;
}

std::string transfer_matrix_markdown(const TransferMatrix& m, const std::string& title) {
  std::ostringstream s;
  s << "# " << title
    << "\n\nTransfer matrix (response output / input; factors as in the report: [s/a + 1] "
    << "a stable real root, [1 - s/a] a right-half-plane zero, [(s/w)^2 + 2(z)s/w + 1] a "
       "pair).\n\n| |";
  for (const auto& i : m.inputs) s << " " << i << " |";
  s << "\n|---|";
  for (size_t k = 0; k < m.inputs.size(); ++k) s << "---|";
  s << "\n";
  for (const auto& o : m.outputs) {
    s << "| **" << o << "** |";
    for (const auto& i : m.inputs) {
      auto it = m.fits.find({o, i});
      if (it == m.fits.end()) {
        s << " |";
        continue;
      }
      const FitResult& f = it->second;
      if (f.status == FitResult::Status::kNoResponse) {
        s << " 0<br>*no response above the noise* |";
        continue;
      }
      s << " " << tf_to_text(f.tf) << "<br>*" << f.status_str() << ", order " << f.num_order << "/"
        << f.den_order;
      if (f.chi2_per_dof >= 0) s << ", chi2/dof " << num(f.chi2_per_dof);
      s << "* |";
    }
    s << "\n";
  }
  s << "\n## Common poles (" << m.state_count
    << " states)\n\n| pole | scope | paths |\n|---|---|---|\n";
  for (const auto& c : m.clusters) {
    s << "| " << factor_text(c.mean) << " | " << c.scope << (c.where.empty() ? "" : " " + c.where)
      << " | ";
    for (size_t k = 0; k < c.pairs.size(); ++k) s << (k ? ", " : "") << c.pairs[k];
    s << " |\n";
  }
  return s.str();
}

}  // namespace fralab
