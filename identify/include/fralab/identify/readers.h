// Frequency-response input for `fralab fit` (docs/formats.md §4): fralab-frd/1 JSON, CSV with a
// header naming its columns (w or f_hz; mag or mag_db; phase_deg; or re, im; optional sigma), and
// the report's TFNS card decks (Appendix B).
//
// TFNS deck: a program control group ended by a "*" card, then frequency-response cards ended by
// "*". Control cards: "C" (cols 2-10 denominator starting order, 11-20 numerator starting order,
// 21-30 equation error tolerance c_phi, 31-40 real error tolerance c_N, 41-50 frequency scale
// factor (ignored: fralab scales automatically), 51-60 term rejection criterion), "O" (plot,
// ignored), "Z"/"P" (root deletion: A4 fields "P03", "Z02", ... from column 1; a blank field ends
// the scan). Data cards, in ascending frequency: column 1 type (blank or B: Bode gain dB and phase
// degrees; P: magnitude and angle radians; R: real and imaginary), columns 15-29 frequency (rad/s;
// "H" in column 15: Hz, "R": rad/s), 30-44 part 1 ("D" in column 30: dB, "M": magnitude), 45-59
// part 2
// ("D" in column 45: degrees, "R": radians). Errors name the file and line.
#pragma once

#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/identify/tfns.h"

namespace fralab {

struct FitInput {
  Frd frd;
  bool has_control = false;            // a TFNS "C" card was read
  FitOptions options;                  // from the "C" card
  std::vector<std::string> deletions;  // "P03", "Z02" (1-based root numbers)
};

/// Reads any of the three formats (by content: '{' JSON, a header with commas CSV, else a deck).
FitInput read_fit_input(const std::string& file);
Frd read_frd_csv(const std::string& file);
FitInput read_tfns_deck(const std::string& file);

/// Deletes roots named like "P03" / "Z02" (1-based, in the fit's listing order: ascending
/// frequency); a pair counts as one root. The DC gain is kept. InputError for an unknown number.
Tf delete_roots(const Tf& tf, const std::vector<std::string>& which);

}  // namespace fralab
