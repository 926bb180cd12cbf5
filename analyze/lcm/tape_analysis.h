// LCM edge of the analyser: decoding tape records into PairAnalyzers, the same code for live
// subscribers and for reading a tape file directly (so live, replayed and offline agree exactly).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fralab/analyze/pair_analyzer.h"
#include "fralab/lcm_io.h"

namespace fralab {

/// Feeds tape records to a set of pair analysers. Records of another run id are ignored once the
/// run id is known (the first record fixes it unless one is given).
class TapeFeeder {
 public:
  TapeFeeder(const std::vector<std::string>& pairs, const AnalyzerOptions& opt,
             std::string run_id = "");
  /// Decodes and dispatches one record; InputError names the channel for a wrong message type.
  /// Returns the tape seq for a tape block (else -1).
  int64_t feed(const std::string& channel, const void* data, int size);
  std::vector<std::unique_ptr<PairAnalyzer>>& analyzers() { return an_; }
  /// The run's final tape block has arrived and every analyser has resolved its windows.
  bool all_done() const;
  void flush();
  const std::string& run_id() const { return run_id_; }

 private:
  std::vector<std::unique_ptr<PairAnalyzer>> an_;
  std::string run_id_;
  bool final_seen_ = false;
};

/// Offline tape mode: every pair over the whole tape file, flushed at the end.
std::vector<Frd> analyze_tape_file(const std::string& path, const std::vector<std::string>& pairs,
                                   const AnalyzerOptions& opt);

}  // namespace fralab
