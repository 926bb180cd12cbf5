#include "fralab/lab/data_check.h"

#include <filesystem>
#include <iostream>

#include "fralab/analyze/pair_analyzer.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/lcm/tape_file.h"

namespace fralab {

CheckedTape check_tape(const std::string& tape, const std::string& run_id,
                       const std::vector<std::string>& pairs, const DataQualityOptions& o) {
  // The run, its series and a mended copy are held in memory together.
  std::error_code ec;
  const uintmax_t bytes = std::filesystem::file_size(tape, ec);
  if (ec) throw InputError(tape + ": cannot be read: " + ec.message());
  if (bytes > kMaxCheckedTapeBytes)
    throw InputError(tape + ": " + std::to_string(bytes / 1000000) +
                     " MB, more than the data-quality checks hold in memory (" +
                     std::to_string(kMaxCheckedTapeBytes / 1000000) + " MB)");
  const TapeRun run = read_tape_run(tape, run_id);
  const TimeSeries series = blocks_to_series(run.blocks, tape);
  const Schedule schedule{series.sample_rate_hz, run.run_id, run.events};
  CheckedTape out;
  out.quality = check_data_quality(series, schedule, o);
  if (!out.quality.changes_curves()) return out;
  const std::vector<Block> blocks = series_to_blocks(mend_series(series, out.quality, schedule),
                                                     schedule, run.blocks.front().n_samples);
  out.mended_curves = analyse_run_in_memory(schedule.events, blocks, pairs);
  widen_for_mending(*out.mended_curves, out.quality);
  return out;
}

void print_data_quality(const DataQuality& q) {
  for (const DataFault& f : q.faults)
    std::cerr << "fralab: data quality: " << f.text << "; " << f.action << "\n";
}

}  // namespace fralab
