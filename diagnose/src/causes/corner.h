// Internal: the real-corner cause, whose two units are missing_lag (F = 1/(1 + s/a),
// missing_lag.cc) and missing_lead (F = 1 + s/a, missing_lead.cc). One search: log-spaced corner a
// over the measured band widened by DiagnoseOptions::corner_decades_beyond on each side, grid then
// Brent's method. Consistent across pairs within DiagnoseOptions::consistent_rel; the primary
// parameter is the corner, which the simulation lacks (docs/method/diagnosis.md, "The catalogue").
#pragma once

#include "cause.h"

namespace fralab::diag {

/// One candidate {kind, corner_rad_s = a}.
Cause fit_corner(CauseKind kind, bool lead, const PairFit& p, const DiagnoseOptions& opt);

/// What missing_lag and missing_lead share; each says which it is (lead()), how it extends a tf and
/// what it shows.
class CornerCause : public LinearCause {
 public:
  void fit(const Model&, const PairFit& p, const DiagnoseOptions& opt,
           std::vector<Cause>* out) const final {
    out->push_back(fit_corner(kind(), lead(), p, opt));
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const final {
    return params_within(a, b, {Param::kCornerRadS}, opt.consistent_rel);
  }
  PrimaryParameter primary_parameter(const Finding&) const final {
    return {Param::kCornerRadS, std::nullopt};
  }
  IntervalDomain interval_domain() const final { return {true, 1e-6}; }  // a corner stays > 0

 protected:
  virtual bool lead() const = 0;
};

}  // namespace fralab::diag
