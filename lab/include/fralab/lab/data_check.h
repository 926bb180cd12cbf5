// A recorded run's data checked before its curves are trusted (exchange/data_quality.h), where the
// lab reads a tape: at the end of `fralab measure` and in `fralab analyze`. The tape is never
// changed; when a fault was mended, the run's pairs are analysed again from the mended series.
#pragma once

#include <cstdint>
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

}  // namespace fralab
