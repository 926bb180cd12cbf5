// Stage 5, scope (docs/method/diagnosis.md, "The stages"): the same cause with consistent
// parameters in every measured path into one output is one finding at that output (its sensor), in
// every path from one input one finding at that input (its actuator or calibration), everywhere
// one finding of the plant; what is left stays with its path (or, on an actuator pair, its input).
// The findings fitted jointly over several pairs come first. Path findings that become consistent
// over a scope after the joint sizing are joined by regroup (regroup.cc).
#include <algorithm>
#include <cmath>
#include <functional>

#include "stages.h"

namespace fralab::diag {

bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) {
  if (a.cause != b.cause || a.detail != b.detail) return false;
  for (const auto& [k, v] : a.params)
    if (!b.params.count(k)) return false;
  const CauseUnit* unit = cause_unit(a.cause);
  return unit && unit->consistent(a, b, opt);
}

namespace {

// Whether pc moves or re-damps a simulated pair that a mode finding (stage 3b) moved over pc's
// pair.
bool moved_as_mode(const DiagnosisRun& r, const PairCause& pc) {
  const Cause& c = pc.c;
  const std::optional<Param> key = moved_root_key(c.cause);
  if (!key || !c.params.count(*key)) return false;
  const double wn = c.params.at(*key);
  const std::string& pair = r.pairs[pc.pair].pair;
  for (const Finding& f : r.mode_findings) {
    const double fw = f.parameters.count(Param::kFromRadS) ? f.parameters.at(Param::kFromRadS)
                                                           : f.parameters.at(Param::kWnRadS);
    if (std::abs(fw - wn) <= 1e-3 * fw &&
        std::find(f.pairs.begin(), f.pairs.end(), pair) != f.pairs.end())
      return true;
  }
  return false;
}

// The finding of cause c at a scope, its parameters the mean of its members' (indices into raw).
Finding make_finding(const DiagnosisRun& r, const Cause& c, Scope scope, const std::string& in,
                     const std::string& out, const std::vector<size_t>& members) {
  Finding f;
  f.cause = c.cause;
  f.scope = scope;
  f.input = in;
  f.output = out;
  // Average the members' parameters.
  for (const auto& [key, v] : c.params) {
    double s = 0;
    for (size_t m : members) s += r.raw[m].c.params.at(key);
    f.parameters[key] = s / members.size();
  }
  f.parameters.erase(Param::kNotch);
  if (c.detail == "notch") f.text_parameters["shape"] = "notch";
  for (size_t m : members) f.pairs.push_back(r.pairs[r.raw[m].pair].pair);
  return f;
}

// One finding at `scope` per cause fitted consistently on every position pair `sel` takes (at
// least min_pairs of them); its members are marked used. Actuator pairs are the input's own.
void group(DiagnosisRun& r, std::vector<bool>& used, const std::function<bool(const PairFit&)>& sel,
           Scope scope, const std::string& in, const std::string& out, size_t min_pairs) {
  const std::vector<PairFit>& pairs = r.pairs;
  const std::vector<PairCause>& raw = r.raw;
  std::vector<size_t> members_pairs;
  for (size_t k = 0; k < pairs.size(); ++k)
    if (!pairs[k].output.empty() && sel(pairs[k])) members_pairs.push_back(k);
  if (members_pairs.size() < min_pairs) return;
  for (size_t a = 0; a < raw.size(); ++a) {
    if (used[a] || pairs[raw[a].pair].output.empty() || !sel(pairs[raw[a].pair])) continue;
    std::vector<size_t> m{a};
    for (size_t b = 0; b < raw.size(); ++b) {
      if (b == a || used[b] || pairs[raw[b].pair].output.empty() || !sel(pairs[raw[b].pair]))
        continue;
      if (!consistent(raw[a].c, raw[b].c, r.opt)) continue;
      bool dup = false;
      for (size_t x : m) dup |= raw[x].pair == raw[b].pair;
      if (!dup) m.push_back(b);
    }
    if (m.size() != members_pairs.size()) continue;
    for (size_t x : m) used[x] = true;
    r.findings.push_back(make_finding(r, raw[a].c, scope, in, out, m));
  }
}

}  // namespace

void scope(DiagnosisRun& r) {
  // A pair's own move of a root that the modes stage moved over the pair is that mode again.
  std::erase_if(r.raw, [&](const PairCause& pc) { return moved_as_mode(r, pc); });
  std::vector<bool> used(r.raw.size(), false);
  r.findings = r.state_findings;
  r.findings.insert(r.findings.end(), r.coupling_findings.begin(), r.coupling_findings.end());
  r.findings.insert(r.findings.end(), r.path_findings.begin(), r.path_findings.end());
  r.findings.insert(r.findings.end(), r.mode_findings.begin(), r.mode_findings.end());
  group(
      r, used, [](const PairFit&) { return true; }, Scope::kPlant, "", "", 3);
  for (const auto& o : r.sim.outputs)
    group(
        r, used, [&](const PairFit& p) { return p.output == o.name; }, Scope::kOutput, "", o.name,
        2);
  for (const auto& i : r.sim.inputs)
    group(
        r, used, [&](const PairFit& p) { return p.input == i.name; }, Scope::kInput, i.name, "", 2);
  for (size_t a = 0; a < r.raw.size(); ++a) {
    if (used[a]) continue;
    const PairFit& p = r.pairs[r.raw[a].pair];
    r.findings.push_back(make_finding(
        r, r.raw[a].c, p.output.empty() ? Scope::kInput : Scope::kPath, p.input, p.output, {a}));
    if (!r.raw[a].c.detail.empty()) r.findings.back().explanation = r.raw[a].c.detail;
  }
}

}  // namespace fralab::diag
