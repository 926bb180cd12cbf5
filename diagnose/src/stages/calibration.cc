// Stage 5d, additive causes across scopes (docs/method/diagnosis.md, "The stages"): a gain or a
// delay at an input and another at an output add up on the path between them (dB and seconds),
// so that path's own fit holds their sum and vetoes both groups. For each additive cause
// (gain_mismatch in gain_db, time_delay in delay_s), the total the findings give each X:O pair,
// T(i, o), is explained by carriers, a value a_i per chosen input and b_o per chosen output:
// every choice of carriers among the inputs and outputs that touch a nonzero total (at most
// kMaxCarriers) is fitted by least squares, T(i, o) ~ sum of the carriers on (i, o), over the pairs
// a carrier covers; a pair whose residual is beyond the cause's consistency tolerance keeps a path
// finding of that residual. The choice with the fewest findings (then the smallest residual)
// replaces the findings when it has fewer than they, and when no pair's chi2 rises by more than
// one parameter's BIC penalty, ln 2N over its N points. A delay stays >= 0, carriers and
// residuals alike. A carrier is named by the pairs it covers, as the scope stage names a group.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>

#include "stages.h"

namespace fralab::diag {
namespace {

constexpr size_t kMaxCarriers = 12;  // 2^12 choices at most

struct Additive {
  CauseKind cause;
  Param key;
};

struct Choice {
  std::vector<std::string> inputs, outputs;  // the carriers
  std::vector<double> a, b;                  // their values
  std::map<std::string, double> residual;    // pair -> residual kept as a path finding
  size_t count = 0;
  double ss = 0;
};

// One additive cause's totals over the X:O pairs and the carriers that may explain them.
class Decomposition {
 public:
  Decomposition(const DiagnosisRun& r, Additive ad) : ad_(ad) {
    delay_ = ad.cause == CauseKind::kTimeDelay;
    tol_ = delay_ ? r.opt.consistent_delay_s : r.opt.consistent_gain_db;
    for (const PairFit& p : r.pairs)
      if (!p.output.empty()) {
        pairs_.push_back(p.pair);
        ends_[p.pair] = {p.input, p.output};
      }
  }

  // The cause's findings on X:O pairs at a path, an input or an output (indices into fs); none
  // where the plant holds one, which leaves the cause be.
  std::vector<size_t> findings_of_cause(const std::vector<Finding>& fs) const {
    std::vector<size_t> mine;
    for (size_t x = 0; x < fs.size(); ++x) {
      const Finding& f = fs[x];
      if (f.cause != ad_.cause || f.tf || !f.text_parameters.empty() ||
          !f.parameters.count(ad_.key))
        continue;
      if (f.scope == Scope::kPlant) return {};
      bool on_paths = !f.pairs.empty();
      for (const std::string& q : f.pairs) on_paths &= ends_.count(q) > 0;
      if (on_paths) mine.push_back(x);
    }
    return mine;
  }

  // The choice of carriers with the fewest findings (then the smallest residual) over the totals
  // of fs[mine], among the inputs and outputs that touch a nonzero total; nullopt when there are
  // none or more than kMaxCarriers.
  std::optional<Choice> best_choice(const std::vector<Finding>& fs,
                                    const std::vector<size_t>& mine) {
    for (const std::string& q : pairs_) total_[q] = 0;
    for (size_t x : mine)
      for (const std::string& q : fs[x].pairs) total_[q] += fs[x].parameters.at(ad_.key);
    std::vector<std::string> cand_in, cand_out;
    for (const auto& [q, t] : total_) {
      if (std::abs(t) <= tol_) continue;
      const auto& [i, o] = ends_.at(q);
      if (std::find(cand_in.begin(), cand_in.end(), i) == cand_in.end()) cand_in.push_back(i);
      if (std::find(cand_out.begin(), cand_out.end(), o) == cand_out.end()) cand_out.push_back(o);
    }
    const size_t nc = cand_in.size() + cand_out.size();
    if (nc == 0 || nc > kMaxCarriers) return std::nullopt;
    std::set<std::string> all_in, all_out;
    for (const auto& [q, e] : ends_) all_in.insert(e.first), all_out.insert(e.second);
    std::optional<Choice> best;
    for (uint32_t mask = 1; mask < (1u << nc); ++mask) {
      Choice c;
      for (size_t k = 0; k < nc; ++k)
        if (mask & (1u << k))
          (k < cand_in.size() ? c.inputs : c.outputs)
              .push_back(k < cand_in.size() ? cand_in[k] : cand_out[k - cand_in.size()]);
      // Every input and every output a carrier: one value could move from the ones to the others.
      if (c.inputs.size() == all_in.size() && c.outputs.size() == all_out.size()) continue;
      if (!fit(c)) continue;
      if (!best || c.count < best->count || (c.count == best->count && c.ss < best->ss))
        best = std::move(c);
    }
    return best;
  }

  // The findings of choice c: one per carrier, named by the pairs it covers as the scope stage
  // names a group, and one per pair's residual at its path.
  std::vector<Finding> findings_of(const Choice& c) const {
    std::vector<Finding> out;
    for (size_t k = 0; k < c.inputs.size(); ++k)
      out.push_back(carrier(Scope::kInput, c.inputs[k], "", c.a[k]));
    for (size_t k = 0; k < c.outputs.size(); ++k)
      out.push_back(carrier(Scope::kOutput, "", c.outputs[k], c.b[k]));
    for (const auto& [q, res] : c.residual) {
      Finding f;
      f.cause = ad_.cause;
      f.scope = Scope::kPath;
      f.input = ends_.at(q).first;
      f.output = ends_.at(q).second;
      f.parameters[ad_.key] = res;
      f.pairs = {q};
      out.push_back(f);
    }
    return out;
  }

  const std::vector<std::string>& pairs() const { return pairs_; }

 private:
  // c's carriers fitted by least squares over the pairs they cover, T(i, o) ~ a_i + b_o, and the
  // residual of every pair; false where the pairs cannot tell the carriers apart, a carrier
  // carries nothing, or a delay comes out negative.
  bool fit(Choice& c) const {
    const size_t n = c.inputs.size() + c.outputs.size();
    std::vector<std::string> covered;
    for (const std::string& q : pairs_) {
      const auto& [i, o] = ends_.at(q);
      if (std::count(c.inputs.begin(), c.inputs.end(), i) ||
          std::count(c.outputs.begin(), c.outputs.end(), o))
        covered.push_back(q);
    }
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(Eigen::Index(covered.size()), Eigen::Index(n));
    Eigen::VectorXd t(Eigen::Index(covered.size()));
    for (size_t row = 0; row < covered.size(); ++row) {
      const auto& [i, o] = ends_.at(covered[row]);
      for (size_t k = 0; k < c.inputs.size(); ++k)
        if (c.inputs[k] == i) A(Eigen::Index(row), Eigen::Index(k)) = 1;
      for (size_t k = 0; k < c.outputs.size(); ++k)
        if (c.outputs[k] == o) A(Eigen::Index(row), Eigen::Index(c.inputs.size() + k)) = 1;
      t(Eigen::Index(row)) = total_.at(covered[row]);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    if (qr.rank() < Eigen::Index(n)) return false;  // carriers the pairs cannot tell apart
    const Eigen::VectorXd v = qr.solve(t);
    for (Eigen::Index k = 0; k < v.size(); ++k)  // a carrier of nothing is not one
      if (!(std::abs(v(k)) > tol_ && (!delay_ || v(k) > 0))) return false;
    c.a.assign(v.data(), v.data() + c.inputs.size());
    c.b.assign(v.data() + c.inputs.size(), v.data() + n);
    c.count = n;
    bool ok = true;
    for (const std::string& q : pairs_) {
      const auto& [i, o] = ends_.at(q);
      double carried = 0;
      for (size_t k = 0; k < c.inputs.size(); ++k)
        if (c.inputs[k] == i) carried += c.a[k];
      for (size_t k = 0; k < c.outputs.size(); ++k)
        if (c.outputs[k] == o) carried += c.b[k];
      const double res = total_.at(q) - carried;
      c.ss += res * res;
      if (std::abs(res) <= tol_) continue;
      if (delay_ && res < 0) ok = false;  // a negative delay is no path's
      c.residual[q] = res;
      ++c.count;
    }
    return ok;
  }

  // A carrier's finding. Every pair, three or more: the plant's (one input's carrier on a
  // one-input plant); one pair alone: its path (one output's carrier on a one-input plant).
  Finding carrier(Scope scope, const std::string& in, const std::string& out, double value) const {
    Finding f;
    f.cause = ad_.cause;
    f.scope = scope;
    f.input = in;
    f.output = out;
    f.parameters[ad_.key] = value;
    for (const std::string& q : pairs_)
      if ((!in.empty() && ends_.at(q).first == in) || (!out.empty() && ends_.at(q).second == out))
        f.pairs.push_back(q);
    if (f.pairs.size() >= 3 && f.pairs.size() == pairs_.size()) {
      f.scope = Scope::kPlant, f.input = "", f.output = "";
    } else if (f.pairs.size() == 1) {
      f.scope = Scope::kPath, f.input = ends_.at(f.pairs[0]).first,
      f.output = ends_.at(f.pairs[0]).second;
    }
    return f;
  }

  Additive ad_;
  bool delay_ = false;
  double tol_ = 0;
  std::vector<std::string> pairs_;                                   // the X:O pairs measured
  std::map<std::string, std::pair<std::string, std::string>> ends_;  // pair -> (input, output)
  std::map<std::string, double> total_;                              // pair -> T(i, o)
};

}  // namespace

bool decompose(DiagnosisRun& r) {
  bool changed = false;
  for (const Additive& ad : {Additive{CauseKind::kGainMismatch, Param::kGainDb},
                             Additive{CauseKind::kTimeDelay, Param::kDelayS}}) {
    Decomposition d(r, ad);
    std::vector<Finding>& fs = r.findings;
    const std::vector<size_t> mine = d.findings_of_cause(fs);
    if (mine.size() < 2) continue;
    const std::optional<Choice> best = d.best_choice(fs, mine);
    if (!best || best->count >= mine.size()) continue;
    // The new findings in place of the cause's.
    std::vector<Finding> joined;
    for (size_t x = 0; x < fs.size(); ++x)
      if (std::find(mine.begin(), mine.end(), x) == mine.end()) joined.push_back(fs[x]);
    for (Finding& f : d.findings_of(*best)) joined.push_back(std::move(f));
    if (!quiet_over(r, fs, joined, d.pairs())) continue;
    fs = std::move(joined);
    changed = true;
  }
  return changed;
}

}  // namespace fralab::diag
