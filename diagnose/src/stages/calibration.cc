// Stage 5d, additive causes across scopes (docs/method/diagnosis.md, "The stages"): a gain or a
// delay at an input and another at an output add up on the path between them (dB and seconds),
// so that path's own fit holds their sum and vetoes both groups. For each additive cause
// (gain_mismatch in gain_db, time_delay in delay_s), the total the findings give each X:O pair,
// T(i, o), is explained by carriers, a value a_i per chosen input and b_o per chosen output:
// every choice of carriers among the inputs and outputs that touch a nonzero total (at most
// kMaxCarriers) is fitted by least squares, T(i, o) ~ sum of the carriers on (i, o), over the pairs
// a carrier covers, then again with the pair of the largest residual left out while one is beyond
// the tolerance (the fit with the fewest findings is the choice's); a pair whose residual is
// beyond the cause's consistency tolerance keeps a path finding of that residual. The choice with
// the fewest findings (then the smallest residual, then the smallest carriers) replaces the
// findings when it has fewer than they, or, for delays that were all paths', as many (the delay a
// sensor's or an actuator's paths share is preferred to as many path delays), and when no pair's
// chi2 rises by more than one parameter's BIC penalty, ln 2N over its N points. A delay stays >= 0,
// carriers and residuals alike. A carrier is named by the pairs it covers, as the scope stage names
// a group.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
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
      if (f.cause != ad_.cause || !f.by_value() || !f.parameters.count(ad_.key)) continue;
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
      if (!best || better(c, *best)) best = std::move(c);
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
  // Fewer findings, then a smaller residual; where the residuals are the same (carriers that
  // explain every pair alike: with every input and output measured, a value moved from the
  // inputs' carriers to the outputs' changes no path), the smaller carriers, sum of squares.
  bool better(const Choice& c, const Choice& best) const {
    if (c.count != best.count) return c.count < best.count;
    if (std::abs(c.ss - best.ss) > 1e-6 * tol_ * tol_) return c.ss < best.ss;
    auto size = [](const Choice& x) {
      double v = 0;
      for (const std::vector<double>* side : {&x.a, &x.b})
        for (double y : *side) v += y * y;
      return v;
    };
    return size(c) < size(best);
  }

  // c's carriers fitted to the pairs they cover, T(i, o) ~ a_i + b_o: by least squares over
  // every covered pair, then again with the pair of the largest residual left out (for a delay
  // the largest positive one: a carrier is the part its paths share) while a residual is beyond
  // the tolerance and the rest still tell the carriers apart. Least squares spreads one path's
  // own value over its carrier's other paths; the fit with the fewest findings (then the
  // smallest sum of squared residuals) is c's. False where no fit tells the carriers apart with
  // each carrying something and no delay negative.
  bool fit(Choice& c) const {
    std::vector<std::string> rows;
    for (const std::string& q : pairs_)
      if (carried_by(c, q)) rows.push_back(q);
    std::optional<Choice> best;
    while (true) {
      Choice t;
      t.inputs = c.inputs, t.outputs = c.outputs;
      if (!solve(t, rows)) break;
      const bool ok = residuals(t);
      if (ok && (!best || t.count < best->count || (t.count == best->count && t.ss < best->ss)))
        best = t;
      auto worst = rows.end();
      double worst_res = tol_;
      for (auto it = rows.begin(); it != rows.end(); ++it) {
        const double res = t.residual.count(*it) ? t.residual.at(*it) : 0.0;
        const double size = delay_ ? res : std::abs(res);
        if (size > worst_res) worst = it, worst_res = size;
      }
      if (worst == rows.end()) break;
      rows.erase(worst);
    }
    if (!best) return false;
    c = std::move(*best);
    return true;
  }

  // Whether a carrier of c is on pair q.
  bool carried_by(const Choice& c, const std::string& q) const {
    const auto& [i, o] = ends_.at(q);
    return std::count(c.inputs.begin(), c.inputs.end(), i) ||
           std::count(c.outputs.begin(), c.outputs.end(), o);
  }

  // c's carriers by least squares over the pairs `rows`; false where those cannot tell them
  // apart or a carrier carries nothing (or, a delay, less than nothing).
  bool solve(Choice& c, const std::vector<std::string>& rows) const {
    const size_t n = c.inputs.size() + c.outputs.size();
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(Eigen::Index(rows.size()), Eigen::Index(n));
    Eigen::VectorXd t(Eigen::Index(rows.size()));
    for (size_t row = 0; row < rows.size(); ++row) {
      const auto& [i, o] = ends_.at(rows[row]);
      for (size_t k = 0; k < c.inputs.size(); ++k)
        if (c.inputs[k] == i) A(Eigen::Index(row), Eigen::Index(k)) = 1;
      for (size_t k = 0; k < c.outputs.size(); ++k)
        if (c.outputs[k] == o) A(Eigen::Index(row), Eigen::Index(c.inputs.size() + k)) = 1;
      t(Eigen::Index(row)) = total_.at(rows[row]);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    if (qr.rank() < Eigen::Index(n)) return false;  // carriers the pairs cannot tell apart
    const Eigen::VectorXd v = qr.solve(t);
    for (Eigen::Index k = 0; k < v.size(); ++k)  // a carrier of nothing is not one
      if (!(std::abs(v(k)) > tol_ && (!delay_ || v(k) > 0))) return false;
    c.a.assign(v.data(), v.data() + c.inputs.size());
    c.b.assign(v.data() + c.inputs.size(), v.data() + n);
    return true;
  }

  // Every pair's residual under c's carriers, those beyond the tolerance kept as path findings
  // (c.residual, c.count, c.ss); false where one is a negative delay.
  bool residuals(Choice& c) const {
    c.count = c.inputs.size() + c.outputs.size();
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
    if (!best || best->count > mine.size()) continue;
    // As many findings: the delay a place's paths share (a sensor's, an actuator's) is preferred
    // to as many path delays.
    const bool on_paths = std::all_of(mine.begin(), mine.end(),
                                      [&](size_t x) { return fs[x].scope == Scope::kPath; });
    if (best->count == mine.size() && !(ad.cause == CauseKind::kTimeDelay && on_paths)) continue;
    // The new findings in place of the cause's.
    std::vector<Finding> joined;
    for (size_t x = 0; x < fs.size(); ++x)
      if (std::find(mine.begin(), mine.end(), x) == mine.end()) joined.push_back(fs[x]);
    const std::vector<Finding> chosen = d.findings_of(*best);
    if (std::all_of(chosen.begin(), chosen.end(),
                    [](const Finding& f) { return f.scope == Scope::kPath; }) &&
        on_paths)
      continue;  // paths again
    joined.insert(joined.end(), chosen.begin(), chosen.end());
    // The carriers and residuals sized on the data (the totals' least squares weighs every pair
    // alike; the pairs' chi2 does not), the other findings in place.
    std::vector<size_t> group(chosen.size());
    std::iota(group.begin(), group.end(), joined.size() - chosen.size());
    refine(r, joined, group, fitted_pairs(r, d.pairs()), 1);
    if (!quiet_over(r, fs, joined, d.pairs())) continue;
    fs = std::move(joined);
    changed = true;
  }
  return changed;
}

}  // namespace fralab::diag
