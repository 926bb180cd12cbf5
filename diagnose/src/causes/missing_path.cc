#include "missing_path.h"

#include <cmath>

#include "cause.h"
#include "fralab/core/pair_id.h"
#include "fralab/identify/tfns.h"
#include "fralab/identify/transfer_matrix.h"

namespace fralab::diag {

PairFit absent_pair_points(const MeasuredPair& mp, const DiagnoseOptions& opt) {
  PairFit p;
  p.pair = mp.pair;
  const PairId id = PairId::parse(mp.pair);
  p.input = id.input;
  p.output = id.output;
  for (const auto& pt : mp.frd.points)
    if (usable(pt, opt)) add_point(p, pt, 0.0, opt);  // no simulated path: 0
  return p;
}

std::optional<Finding> fit_missing_path(const Model& sim, const PairFit& p,
                                        const DiagnoseOptions& opt, std::string* why) {
  const size_t N = p.w.size();
  if (N < 3) return std::nullopt;
  double c0 = 0;
  for (size_t q = 0; q < N; ++q) c0 += std::norm(p.meas[q]) / (p.sig[q] * p.sig[q]);
  if (c0 <= N + 4 * std::sqrt(double(N))) return std::nullopt;  // within the noise
  // What the model puts around a path: its response with a unit path in place.
  Model unit = sim;
  unit.paths.push_back({p.output, p.input, Tf{}, Json::object()});
  std::vector<FrdPoint> data;
  for (size_t q = 0; q < N; ++q) {
    const auto around = model_pair_response(unit, p.pair, p.w[q], p.amp[q], opt.chain);
    if (!around || std::abs(*around) == 0) continue;
    const C g = p.meas[q] / *around;
    FrdPoint pt;
    pt.w = p.w[q];
    pt.mag = std::abs(g);
    pt.phase_deg = std::arg(g) * 180 / M_PI;
    pt.sigma = p.sig[q] / std::abs(*around);
    data.push_back(pt);
  }
  FitOptions fo;
  fo.max_delay_s = std::max(opt.delay_max_s, 1e-3);
  fo.max_den_order = std::min<int>(6, int(data.size()) / 2);
  FitResult r;
  try {
    fo.validate();
    r = fit_tf(data, fo);
  } catch (const std::exception& e) {
    if (why)
      *why =
          std::string("a response where the simulation has no path, but no path fits: ") + e.what();
    return std::nullopt;
  }
  for (const Root& pole : r.tf.poles)
    if (!pole.stable()) {
      if (why) *why = "a response where the simulation has no path; the path fitted is unstable";
      return std::nullopt;
    }
  Finding f;
  f.cause = CauseKind::kMissingPath;
  f.scope = Scope::kPath;
  f.input = p.input;
  f.output = p.output;
  f.parameters = {{Param::kGain, r.tf.gain},
                  {Param::kDelayS, r.tf.delay_s},
                  {Param::kPoles, double(r.tf.poles.size())},
                  {Param::kZeros, double(r.tf.zeros.size())}};
  f.tf = r.tf;
  f.pairs = {p.pair};
  f.explanation = "a response beyond the noise where the simulation has no path (chi2 " + fmt(c0) +
                  " against zero over " + std::to_string(N) + " points): the path " +
                  tf_to_text(r.tf) + " fitted";
  return f;
}

namespace {

// The missing path as a cause: the fitted tf added as the path X:O (unless the model has one), its
// gain the finding's. A whole path has no one primary parameter: it is resolved by its absence and
// carries no interval. The explanation is written when fitted.
class MissingPath final : public CauseUnit {
 public:
  CauseKind kind() const override { return CauseKind::kMissingPath; }
  const char* name() const override { return "missing_path"; }
  PrimaryParameter primary_parameter(const Finding&) const override {
    return {std::nullopt, std::nullopt};
  }
  void apply(Model& m, const Finding& f) const override {
    if (m.path(f.output, f.input) || !f.tf) return;
    Tf t = *f.tf;
    t.gain = f.parameters.at(Param::kGain);
    m.paths.push_back({f.output, f.input, t, Json::object()});
  }
  std::string explain(const Finding& f) const override { return f.explanation; }
};

}  // namespace

const CauseUnit& missing_path_cause() {
  static const MissingPath c;
  return c;
}

}  // namespace fralab::diag
