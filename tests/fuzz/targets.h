// The fuzz targets, one per reader: each writes the bytes to a scratch file and reads it the way
// fralab does. A clean refusal is an InputError; anything else (a crash, a sanitizer report, any
// other exception escaping) is a finding. Shared by the libFuzzer executables (scripts/fuzz.sh,
// ASan+UBSan) and by fuzz_regression_test, which replays the corpus and every kept crash in the
// ordinary build.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "fralab/lcm/tape_file.h"

namespace fralab::fuzz {

/// The readers fuzzed: "tape" (read_tape_file + the tape analysis), "model" (load_model), "frd"
/// (load_frd), "csv" (read_frd_csv), "tfns" (read_tfns_deck, then read_fit_input's checks),
/// "series" (a CSV recording: read_csv_series, to_time_series, schedule_from_reference),
/// "schedule" (load_schedule), "shapes" (the bytes steer a random identification set,
/// tests/util/random_shapes.h, built into a transfer matrix and a state model of few sweeps).
/// Returns 0 when the input was read, 1 when it was refused with an InputError.
int run(const std::string& reader, const uint8_t* data, size_t size);

}  // namespace fralab::fuzz
