// A recorded run's data checked before its curves are trusted (exchange/data_quality.h), where the
// lab reads a tape: at the end of `fralab measure` and in `fralab analyze`, and again for clocks
// once the campaign's later runs have measured them too. The tape is never changed; when a fault
// was mended, the run's pairs are analysed again from the mended series.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/exchange/data_quality.h"

namespace fralab {

struct CheckedTape {
  DataQuality quality;
  /// The pairs' curves from the mended series, with the faults' uncertainty in their sigmas
  /// (widen_for_mending), in the order asked; nullopt when no fault changes them (the tape's own
  /// analysis stands).
  std::optional<std::vector<Frd>> mended_curves;
};

/// Largest tape the checks read (its run, series and mended copy are held in memory).
inline constexpr uintmax_t kMaxCheckedTapeBytes = 400'000'000;

/// Reads run `run_id` of `tape` ("" its first run), checks it, and when a fault changes the curves
/// analyses `pairs` from the mended series (re-cut into blocks of the tape's own size). A tape
/// whose run has a missing block or whose channels change, and one larger than
/// kMaxCheckedTapeBytes, are refused (InputError naming it): the caller says so and analyses the
/// tape as it is.
CheckedTape check_tape(const std::string& tape, const std::string& run_id,
                       const std::vector<std::string>& pairs, const DataQualityOptions& o = {});

/// One line per fault, "fralab: data quality: TEXT; ACTION", on stderr.
void print_data_quality(const DataQuality& q);

/// The channels whose clock estimates in `all` (every run's own), pooled (pool_clocks,
/// exchange/data_quality.h), stand beyond `o.clock_sigmas` times the pool's sigma and above
/// `o.min_clock`.
std::vector<std::string> pooled_clocks(const std::vector<ClockEstimate>& all,
                                       const DataQualityOptions& o = {});

/// A measurement checked again for clocks once a later run of the campaign (its validation) has
/// estimated them too.
struct ClockRecheck {
  std::vector<std::string> lines;  // one per run that now mends a clock: what it names and does
  /// DIR's curves, those at a newly mended channel replaced (empty when none is): to fit again.
  std::vector<Frd> curves;
  int replaced = 0;   // how many of them
  std::string title;  // DIR's transfer matrix title
};

/// Each run of the measurement in `dir` (DIR itself, or DIR/multisine and DIR/sine of an auto
/// campaign) that did not mend a channel pooled_clocks(all) names is checked again with the
/// other runs' estimates in `all` (those labelled with another folder). Where it now mends it,
/// its pairs are analysed again from the mended series (its frd files and run.json's
/// data_quality replaced), and DIR's curves at that channel which came from it (an auto
/// campaign's merge: a sine input's u_X:X from the sine, the rest from the multisine) are
/// returned replaced. DIR's own files are not touched: refit_after_recheck.
ClockRecheck recheck_clocks(const std::string& dir, const std::vector<ClockEstimate>& all);

/// DIR's curves of `r` saved and fitted again (`fit_delay`, in fralab-identify within timeout_s),
/// DIR/run.json's fit outcome updated (partial when the fit fails). Returns what was done, one
/// line ("" when nothing was replaced).
std::string refit_after_recheck(const std::string& dir, ClockRecheck& r,
                                const std::string& fit_delay, double timeout_s = 3600);

}  // namespace fralab
