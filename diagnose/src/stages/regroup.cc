// Stage 5c, regroup (docs/method/diagnosis.md, "The stages"): after the joint sizing (5b), path
// findings that have become consistent over a whole scope are joined as scope() joins them: two
// effects that overlap on one path can split wrongly in its own fit (a plant pole moved and an
// output's gain, fitted on that path as a larger shift and a smaller gain) and veto the group. A
// scope's pair where no fit found the cause (a weak path) joins the group when the cause costs it
// no more than one parameter's chi2 penalty, and at least as many pairs found it as did not; a
// pair that holds other findings too is diagnosed again, alone, against the simulation extended by
// every other finding (the group's included), and joins on what that finds. The plant's scope
// also joins outputs' and inputs' findings (the plant's mode found output by output where one
// output's own overlap kept the paths apart); a scope of two pairs joins one pair's finding when
// the other, diagnosed again, leaves fewer findings than the paths' own, or as many that fit the
// two pairs better by more than one parameter's penalty. A scope's finding whose
// pairs hold path findings beside it on fewer than half of them has those pairs diagnosed again
// the same way, kept on a lower BIC. A group whose rest pairs were diagnosed again stands on the
// criterion over the scope's pairs (chi2 + k ln 2N, k the findings there) and falls where a rest
// pair would undo its cause; an output's or an input's group is tried even from one pair.
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <set>

#include "stages.h"

namespace fralab::diag {
namespace {

// Whether f undoes g where both apply: a lead on a lag's corner (or a lag on a lead's), within
// consistent_rel, or a gain opposite to g's within consistent_gain_db.
bool undoes(const Finding& f, const Finding& g, const DiagnoseOptions& opt) {
  const bool corners = (f.cause == CauseKind::kMissingLead && g.cause == CauseKind::kMissingLag) ||
                       (f.cause == CauseKind::kMissingLag && g.cause == CauseKind::kMissingLead);
  if (corners) {
    const double a = f.parameters.at(Param::kCornerRadS), b = g.parameters.at(Param::kCornerRadS);
    return std::abs(a - b) <= opt.consistent_rel * b;
  }
  if (f.cause == CauseKind::kGainMismatch && g.cause == CauseKind::kGainMismatch)
    return std::abs(f.parameters.at(Param::kGainDb) + g.parameters.at(Param::kGainDb)) <=
           opt.consistent_gain_db;
  if (f.cause == CauseKind::kTimeDelay && g.cause == CauseKind::kTimeDelay) {
    const double a = f.parameters.at(Param::kDelayS), b = g.parameters.at(Param::kDelayS);
    return std::abs(a + b) <= std::max(opt.consistent_delay_s, opt.consistent_rel * std::abs(b));
  }
  return false;
}

// Whether f, a pair's own finding against the simulation extended by g, is g's effect again where
// g placed it: a root f moves, re-damps or adds (a pole shift's from, a damping error's or a
// resonance's frequency, a lag's or lead's corner) within consistent_rel of the root g placed
// there (a pole shift's to, the others' own), or, for causes without a root, g's cause again
// but a delay or a gain, which compose with g's (a path's own beside its output's).
bool repeats(const Finding& f, const Finding& g, const DiagnoseOptions& opt) {
  auto root = [](const Finding& x, bool placed) -> double {
    Param key;
    switch (x.cause) {
      case CauseKind::kPoleShift:
        key = placed ? Param::kToRadS : Param::kFromRadS;
        break;
      case CauseKind::kDampingError:
      case CauseKind::kMissingResonance:
        key = Param::kWnRadS;
        break;
      case CauseKind::kMissingLag:
      case CauseKind::kMissingLead:
        key = Param::kCornerRadS;
        break;
      default:
        return 0.0;
    }
    return x.parameters.count(key) ? x.parameters.at(key) : 0.0;
  };
  const double a = root(f, false), b = root(g, true);
  if (a > 0 && b > 0) return std::abs(a - b) <= opt.consistent_rel * b;
  return f.cause == g.cause && f.cause != CauseKind::kTimeDelay &&
         f.cause != CauseKind::kGainMismatch;
}

// A path finding of a pair's own diagnosis against an extended model, in the simulation's terms: a
// moved root's frequency (a pole shift's from, a damping error's wn) is the simulation's root on
// that path (its transfer function, its output's sensor, its input's actuator) within 1e-3 of it,
// where the extended model's root sat off by what other findings moved; its explanation is left
// to the summary (stage 9), which names a state model's mode.
Finding in_simulation_terms(const DiagnosisRun& r, Finding f) {
  constexpr double kSameRoot = 1e-3;
  f.explanation.clear();
  const std::optional<Param> key = moved_root_key(f.cause);
  if (!key || !f.parameters.count(*key)) return f;
  double& v = f.parameters.at(*key);
  std::vector<const Tf*> tfs;
  if (const ModelPath* p = r.sim.path(f.output, f.input)) tfs.push_back(&p->tf);
  if (const int o = r.sim.output_index(f.output); o >= 0 && r.sim.outputs[size_t(o)].sensor)
    tfs.push_back(&*r.sim.outputs[size_t(o)].sensor);
  if (const int i = r.sim.input_index(f.input); i >= 0 && r.sim.inputs[size_t(i)].actuator)
    tfs.push_back(&*r.sim.inputs[size_t(i)].actuator);
  double best = v, off = kSameRoot * v;
  for (const Tf* t : tfs)
    for (const Root& root : t->poles) {
      const double w = root.pair ? root.wn : -root.real;
      if (std::abs(w - v) <= off) best = w, off = std::abs(w - v);
    }
  v = best;
  return f;
}

// The simulation extended by `fs`, for a pair diagnosed again by its paths: a state model's
// entries are fitted over every pair (stage 3a), not on one, and the model's state_space is the
// simulation's, without the findings.
Model paths_extended_by(const DiagnosisRun& r, const std::vector<Finding>& fs) {
  Model ext = extended_by(r, fs, fs.size());
  ext.state_space.reset();
  return ext;
}

// The pairs `pairs` and every other pair of the findings fs[sized]: where a finding is sized, on
// every pair it covers.
std::vector<std::string> pairs_of(const std::vector<Finding>& fs, const std::vector<size_t>& sized,
                                  std::vector<std::string> pairs) {
  for (size_t x : sized)
    for (const std::string& q : fs[x].pairs)
      if (std::find(pairs.begin(), pairs.end(), q) == pairs.end()) pairs.push_back(q);
  return pairs;
}

// Pair q diagnosed again, alone, against ext (the whole diagnosis on that pair): its findings on
// q alone.
std::vector<Finding> own_findings(const DiagnosisRun& r, const Model& ext, const std::string& q) {
  std::vector<MeasuredPair> one;
  for (const MeasuredPair& mp : r.data)
    if (mp.pair == q) one.push_back(mp);
  std::vector<Finding> out;
  for (const Finding& f : diagnose(ext, one, r.opt).findings)
    if (f.scope == Scope::kPath && f.pairs == std::vector<std::string>{q}) out.push_back(f);
  return out;
}

// The findings `with` (a scope's finding last, over the pairs that found it and the pairs `rest`)
// with the rest's own findings dropped (those on its pairs alone: a path's, or an output's when
// the rest is that output's paths), the scope's finding sized on the pairs that found it together
// with the other findings there, each of those on every pair it covers but the rest's (the members'
// mean carries one pair's own value, off by up to the tolerance, and another finding on that pair
// what it took of the overlap, which the rest would then want moved again), and each rest pair
// diagnosed again, alone, against the simulation extended by all that (the whole diagnosis on that
// pair): the new findings, or nullopt when a rest pair wants the scope's cause again, or wants it
// undone (the cause is not there).
std::optional<std::vector<Finding>> rediagnose_rest(DiagnosisRun& r,
                                                    const std::vector<Finding>& with,
                                                    const std::vector<std::string>& rest) {
  auto in_rest = [&](const std::string& q) {
    return std::find(rest.begin(), rest.end(), q) != rest.end();
  };
  auto own = [&](const Finding& f) {
    if (f.pairs.empty() || f.scope == Scope::kPlant) return false;
    for (const std::string& q : f.pairs)
      if (!in_rest(q)) return false;
    return true;
  };
  std::vector<Finding> base;
  for (size_t x = 0; x + 1 < with.size(); ++x)
    if (!own(with[x])) base.push_back(with[x]);
  base.push_back(with.back());
  std::vector<std::string> found_it;
  for (const std::string& q : base.back().pairs)
    if (!in_rest(q)) found_it.push_back(q);
  std::vector<size_t> sized{base.size() - 1};
  for (size_t x = 0; x + 1 < base.size(); ++x)
    for (const std::string& q : base[x].pairs)
      if (std::find(found_it.begin(), found_it.end(), q) != found_it.end()) {
        sized.push_back(x);
        break;
      }
  // Each on every pair it covers but the rest's (their own findings are dropped), the scope's
  // finding on the pairs that found it.
  const std::vector<size_t> others(sized.begin() + 1, sized.end());
  std::vector<std::string> fit_on;
  for (const std::string& q : pairs_of(base, others, found_it))
    if (!in_rest(q)) fit_on.push_back(q);
  refine(r, base, sized, fitted_pairs(r, fit_on), 1);
  const Model ext = paths_extended_by(r, base);
  std::vector<Finding> out = base;
  for (const std::string& q : rest)
    for (const Finding& f : own_findings(r, ext, q)) {
      if (repeats(f, base.back(), r.opt) || undoes(f, base.back(), r.opt)) return std::nullopt;
      out.push_back(in_simulation_terms(r, f));
    }
  return out;
}

// The scope's finding (with.back(), its pairs the scope's) sized over every pair of the scope at
// once, each pair's other causes found again around it: the path findings on the scope's pairs are
// dropped, the scope's finding is sized together with the findings that remain there (each on
// every pair it covers: an output's delay resized on an input's scope moves its other paths), each
// scope pair is diagnosed again, alone, against the simulation extended by them (its own of the
// last round left out), and its findings of other causes join before the next sizing; rounds repeat
// until no pair's findings change (at most kScopeRounds). Where one member's own fit split an
// overlap (a plant's pole moved and an output's gain, taken on one path as a smaller shift and no
// gain), the members' mean is off and a rest pair wants the cause again at its own value; sized
// with every pair's other causes in place it is not. nullopt when a pair still wants the cause, or
// its undoing, after the last round.
std::optional<std::vector<Finding>> fit_over_scope(DiagnosisRun& r,
                                                   const std::vector<Finding>& with,
                                                   const std::vector<std::string>& scope_pairs) {
  constexpr int kScopeRounds = 4;
  auto in_scope = [&](const std::string& q) {
    return std::find(scope_pairs.begin(), scope_pairs.end(), q) != scope_pairs.end();
  };
  std::vector<Finding> kept;  // the findings that stay as they are, the scope's last
  for (size_t x = 0; x + 1 < with.size(); ++x)
    if (!(with[x].scope == Scope::kPath && with[x].pairs.size() == 1 && in_scope(with[x].pairs[0])))
      kept.push_back(with[x]);
  Finding g = with.back();
  std::vector<Finding> found;  // the scope pairs' own findings of other causes, the last round's
  for (int round = 0; round < kScopeRounds; ++round) {
    std::vector<Finding> base = kept;
    base.insert(base.end(), found.begin(), found.end());
    base.push_back(g);
    std::vector<size_t> sized;
    for (size_t x = 0; x < base.size(); ++x)
      if (std::any_of(base[x].pairs.begin(), base[x].pairs.end(), in_scope)) sized.push_back(x);
    refine(r, base, sized, fitted_pairs(r, pairs_of(base, sized, scope_pairs)), 1);
    g = base.back();
    kept.assign(base.begin(), base.begin() + std::ptrdiff_t(kept.size()));
    // Each pair diagnosed again without its own findings of the last round: they are found anew.
    std::vector<Finding> around = kept;
    around.push_back(g);
    const Model ext = paths_extended_by(r, around);
    std::vector<Finding> again;
    bool wants = false;
    for (const std::string& q : scope_pairs)
      for (const Finding& f : own_findings(r, ext, q)) {
        if (repeats(f, g, r.opt) || undoes(f, g, r.opt))
          wants = true;
        else
          again.push_back(in_simulation_terms(r, f));
      }
    auto same = [](const std::vector<Finding>& a, const std::vector<Finding>& b) {
      if (a.size() != b.size()) return false;
      for (size_t x = 0; x < a.size(); ++x)
        if (a[x].cause != b[x].cause || a[x].pairs != b[x].pairs) return false;
      return true;
    };
    const bool settled = !wants && round > 0 && same(again, found);
    found = std::move(again);
    if (settled) {
      std::vector<Finding> out = kept;
      out.insert(out.end(), found.begin(), found.end());
      out.push_back(g);
      return out;
    }
  }
  return std::nullopt;
}

// "scope:input:output:cause", a scope and cause tried once in a pass.
std::string scope_cause_key(Scope scope, const std::string& in, const std::string& out,
                            CauseKind cause) {
  return std::string(to_string(scope)) + ":" + in + ":" + out + ":" + to_string(cause);
}

// The path findings of `fs` on pair q alone, fs[skip] not counted.
size_t path_findings_on(const std::vector<Finding>& fs, const std::string& q,
                        size_t skip = size_t(-1)) {
  size_t n = 0;
  for (size_t x = 0; x < fs.size(); ++x)
    n += x != skip && fs[x].scope == Scope::kPath && fs[x].pairs == std::vector<std::string>{q};
  return n;
}

// The findings of fs on any of `pairs`.
size_t findings_on(const std::vector<Finding>& fs, const std::vector<std::string>& pairs) {
  size_t n = 0;
  for (const Finding& f : fs)
    n += std::any_of(f.pairs.begin(), f.pairs.end(), [&](const std::string& q) {
      return std::find(pairs.begin(), pairs.end(), q) != pairs.end();
    });
  return n;
}

// One scope's regrouping: path findings of one cause, consistent over the scope's pairs, become
// one finding at the scope, its parameters their mean; the scope's other pairs join it as the
// criterion allows. `refitted` holds the groups whose rest pairs were diagnosed again in this
// pass, over every scope.
class ScopeMerge {
 public:
  ScopeMerge(DiagnosisRun& r, std::set<std::string>& refitted, Scope scope, std::string in,
             std::string out, std::vector<std::string> scope_pairs)
      : r_(r),
        refitted_(refitted),
        scope_(scope),
        in_(std::move(in)),
        out_(std::move(out)),
        pairs_(std::move(scope_pairs)) {}

  // Every group the scope's findings form, one at a time, the list looked at again from its start
  // after each; true when any was formed.
  bool run() {
    bool merged = false;
    for (size_t a = 0; a < r_.findings.size(); ++a) {
      if (!candidate(r_.findings[a])) continue;
      std::optional<std::vector<Finding>> joined = try_group(a);
      if (!joined) continue;
      r_.findings = std::move(*joined);
      merged = true;
      a = size_t(-1);
    }
    return merged;
  }

 private:
  // A group formed from findings[a]: its members (indices), the scope's pairs they do not cover,
  // the findings the group replaces (its members and the rest's own fits of the cause), and
  // whether the rest hold nothing else.
  struct Group {
    std::vector<size_t> members;
    std::vector<std::string> rest;
    std::vector<size_t> replaced;
    size_t covered = 0;
    bool clear = true;
  };

  // A finding narrower than the scope, inside it: a path's, or (for the plant) an output's or an
  // input's, found where the overlap on the others' pairs hid it.
  bool candidate(const Finding& f) const {
    if (!f.by_value() || f.pairs.empty()) return false;
    const bool narrower =
        f.scope == Scope::kPath ||
        (scope_ == Scope::kPlant &&
         (f.scope == Scope::kOutput || (f.scope == Scope::kInput && !f.input.empty())));
    if (!narrower || (f.scope == Scope::kPath && f.pairs.size() != 1)) return false;
    for (const std::string& q : f.pairs)
      if (std::find(pairs_.begin(), pairs_.end(), q) == pairs_.end()) return false;
    return true;
  }

  bool covers(const std::vector<size_t>& m, const std::string& q) const {
    for (size_t x : m) {
      const std::vector<std::string>& p = r_.findings[x].pairs;
      if (std::find(p.begin(), p.end(), q) != p.end()) return true;
    }
    return false;
  }

  // The candidates consistent with findings[a], one per pair, and the scope's other pairs: at most
  // a path finding of the same cause each (its parameter not within the cause's tolerance of the
  // group's), nothing else, for the group to be clear.
  Group group_from(size_t a) const {
    const std::vector<Finding>& fs = r_.findings;
    Group grp;
    const Cause ca{fs[a].cause, fs[a].parameters, {}, 0, 1, ""};
    grp.members = {a};
    for (size_t b = 0; b < fs.size(); ++b) {
      if (b == a || !candidate(fs[b])) continue;
      const Cause cb{fs[b].cause, fs[b].parameters, {}, 0, 1, ""};
      if (!consistent(ca, cb, r_.opt)) continue;
      bool dup = false;
      for (const std::string& q : fs[b].pairs) dup |= covers(grp.members, q);
      if (!dup) grp.members.push_back(b);
    }
    for (const std::string& q : pairs_)
      if (!covers(grp.members, q)) grp.rest.push_back(q);
    grp.covered = pairs_.size() - grp.rest.size();
    grp.replaced = grp.members;
    for (size_t x = 0; x < fs.size(); ++x)
      for (const std::string& q : grp.rest) {
        if (std::find(fs[x].pairs.begin(), fs[x].pairs.end(), q) == fs[x].pairs.end()) continue;
        if (candidate(fs[x]) && fs[x].cause == fs[a].cause)
          grp.replaced.push_back(x);
        else
          grp.clear = false;
      }
    return grp;
  }

  // The group's finding at the scope, over its members' pairs, its parameters the members' each
  // weighted by the pairs it covers.
  Finding finding_of(const Group& grp, size_t a) const {
    const std::vector<Finding>& fs = r_.findings;
    Finding g;
    g.cause = fs[a].cause;
    g.scope = scope_;
    g.input = in_;
    g.output = out_;
    for (const auto& [key, v] : fs[a].parameters) {
      double sum = 0;
      for (size_t x : grp.members) sum += fs[x].parameters.at(key) * double(fs[x].pairs.size());
      g.parameters[key] = sum / double(grp.covered);
    }
    for (size_t x : grp.members)
      g.pairs.insert(g.pairs.end(), fs[x].pairs.begin(), fs[x].pairs.end());
    return g;
  }

  // The findings with the group formed from findings[a] in place of what it replaces, or nullopt
  // where the group does not stand.
  std::optional<std::vector<Finding>> try_group(size_t a) {
    const std::vector<Finding>& fs = r_.findings;
    const Group grp = group_from(a);
    // A scope of two pairs, one holding the cause and the other other findings (a sensor lag
    // where the second path also carries an input's calibration, its own fit a resonance in
    // place of both): the group is tried, and kept only when it explains the scope by fewer
    // findings than the paths' own, or by as many that fit better.
    const bool one_of_two = grp.covered == 1 && grp.rest.size() == 1 && !grp.clear;
    // Fewer pairs found the cause than not (an output's delay sized on one of its paths, taken
    // on another for a lag, off the tolerance on a third): an output's or an input's group is
    // tried with its rest diagnosed again, and kept on the criterion; the plant's is not.
    const bool few = !grp.rest.empty() && (grp.covered < 2 || grp.covered < grp.rest.size());
    if (few && !one_of_two && scope_ == Scope::kPlant) return std::nullopt;
    const Finding g = finding_of(grp, a);
    std::vector<Finding> joined;
    for (size_t x = 0; x < fs.size(); ++x)
      if (std::find(grp.replaced.begin(), grp.replaced.end(), x) == grp.replaced.end())
        joined.push_back(fs[x]);
    joined.push_back(g);
    if (grp.rest.empty()) return joined;
    // A pair of the scope whose own fit did not find the cause, or found it off the group's
    // value (a weak path: its points few or noisy), joins the group when the group's cause
    // there costs no more chi2 than one parameter's BIC penalty, ln 2N over its N points, above
    // what it had: the data cannot tell the two apart, and the scope is what the pairs that can
    // tell say. A pair the group's cause fits worse keeps the findings per path. Joined as they
    // stand when the rest held only their own fits of the cause and the group's value is as good
    // there; otherwise the rest pairs are diagnosed again (a rest pair that holds other findings
    // of its own, fitted beside its own value of the cause, which may have taken part of them: a
    // lag fitted as a resonance beside a pole moved too little; or one whose own fit of the cause
    // took another effect in, as an output's gain).
    for (const std::string& q : grp.rest) joined.back().pairs.push_back(q);
    if (grp.clear && !few && quiet_over(r_, fs, joined, grp.rest)) return joined;
    std::optional<std::vector<Finding>> again = sized_again(g, joined, grp.rest);
    if (!again || (one_of_two && again->size() > fs.size())) return std::nullopt;
    return again;
  }

  // The group (g over its members, joined.back() over the scope) with its rest pairs diagnosed
  // again, or sized over every pair of the scope, kept on the criterion; nullopt where it falls.
  std::optional<std::vector<Finding>> sized_again(const Finding& g,
                                                  const std::vector<Finding>& joined,
                                                  const std::vector<std::string>& rest) {
    // Once per scope, cause and members in a pass: every finding of the group is a candidate
    // that forms the same group, and the pairs' diagnoses would only be run again. A group of
    // other members (one whose own fit did not split an overlap) is another group.
    std::vector<std::string> members = g.pairs;
    std::sort(members.begin(), members.end());
    std::string key = scope_cause_key(scope_, in_, out_, g.cause);
    for (const std::string& q : members) key += ":" + q;
    if (!refitted_.insert(key).second) return std::nullopt;
    std::optional<std::vector<Finding>> again = rediagnose_rest(r_, joined, rest);
    if (!again) again = fit_over_scope(r_, joined, pairs_);
    // A pair that wants the cause again is not the group's (and the merge would leave a path
    // finding of the cause to be grouped again).
    if (!again) return std::nullopt;
    // The rest's new findings may only undo the group's cause there (a lead under a lag taken to
    // the plant): the group stands when it explains the scope's pairs by the criterion, its
    // findings on them against theirs before; by as many findings, only when it fits them better
    // by more than one parameter's penalty (a scope of two pairs with a moved mode and a gain on
    // both, one path's own fit splitting them otherwise: the next pass then joins what the refit
    // found).
    const std::vector<Finding>& fs = r_.findings;
    const auto sp = fitted_pairs(r_, pairs_);
    const int dk = int(findings_on(*again, pairs_)) - int(findings_on(fs, pairs_));
    const bool stands = quiet_over(r_, fs, *again, rest) &&
                        earned(chi2_of(r_, extended_by(r_, fs, fs.size()), sp),
                               chi2_of(r_, extended_by(r_, *again, again->size()), sp),
                               points_of(sp), dk >= 0 ? dk + 1 : dk) > 0;
    if (!stands) return std::nullopt;
    return again;
  }

  DiagnosisRun& r_;
  std::set<std::string>& refitted_;
  const Scope scope_;
  const std::string in_, out_;
  const std::vector<std::string> pairs_;
};

// A scope's finding whose pairs hold path findings beside it, on fewer than half its pairs: on
// such a pair the scope's cause took its value from a fit that also split an overlap there (the
// slow mode moved in every path and one path's lag, that path's pole found 8 % off and its lag as
// a resonance). Those pairs are diagnosed again against the scope's finding sized on its other
// pairs; kept when that explains the scope's pairs with a lower BIC, chi2 + k ln 2N with k the
// path findings on those pairs. True when any was.
bool sized_on_clear_pairs(DiagnosisRun& r) {
  bool changed = false;
  std::set<std::string> members_tried;
  for (size_t gi = 0; gi < r.findings.size(); ++gi) {
    std::vector<Finding>& fs = r.findings;
    const Finding& g = fs[gi];
    if (g.scope == Scope::kPath || !g.by_value() || g.pairs.size() < 2) continue;
    std::vector<std::string> extra;
    size_t k_before = 0;
    for (const std::string& q : g.pairs) {
      const size_t here = path_findings_on(fs, q, gi);
      if (here) extra.push_back(q);
      k_before += here;
    }
    if (extra.empty() || 2 * extra.size() > g.pairs.size()) continue;
    if (!members_tried.insert(scope_cause_key(g.scope, g.input, g.output, g.cause)).second)
      continue;
    std::vector<Finding> with;
    for (size_t x = 0; x < fs.size(); ++x)
      if (x != gi) with.push_back(fs[x]);
    with.push_back(g);
    std::optional<std::vector<Finding>> again = rediagnose_rest(r, with, extra);
    if (!again) continue;
    size_t k_after = 0;
    for (const std::string& q : extra) k_after += path_findings_on(*again, q);
    const auto gp = fitted_pairs(r, g.pairs);
    const double pen = bic_penalty(gp);
    const double bic_before =
        chi2_of(r, extended_by(r, fs, fs.size()), gp) + double(k_before) * pen;
    const double bic_after =
        chi2_of(r, extended_by(r, *again, again->size()), gp) + double(k_after) * pen;
    if (!(bic_after < bic_before - pen)) continue;
    fs = std::move(*again);
    changed = true;
    gi = size_t(-1);  // the list changed: look again from its start
  }
  return changed;
}

}  // namespace

bool regroup(DiagnosisRun& r) {
  bool merged = false;
  std::set<std::string> refitted;  // scope, cause and members whose rest pairs were tried again
  // Every position pair `sel` takes (at least min_pairs) is one scope.
  auto merge = [&](const std::function<bool(const PairFit&)>& sel, Scope scope,
                   const std::string& in, const std::string& out, size_t min_pairs) {
    std::vector<std::string> scope_pairs;
    for (const PairFit& p : r.pairs)
      if (!p.output.empty() && sel(p)) scope_pairs.push_back(p.pair);
    if (scope_pairs.size() < min_pairs) return;
    merged |= ScopeMerge(r, refitted, scope, in, out, std::move(scope_pairs)).run();
  };
  merge([](const PairFit&) { return true; }, Scope::kPlant, "", "", 3);
  for (const auto& o : r.sim.outputs)
    merge([&](const PairFit& p) { return p.output == o.name; }, Scope::kOutput, "", o.name, 2);
  for (const auto& i : r.sim.inputs)
    merge([&](const PairFit& p) { return p.input == i.name; }, Scope::kInput, i.name, "", 2);
  merged |= one_per_place(r.findings);
  merged |= moved_roots_folded(r);
  merged |= sized_on_clear_pairs(r);
  return merged;
}

}  // namespace fralab::diag
