// LCM edge of the analyser: decoding tape records into PairAnalyzers, the same code for live
// subscribers and for reading a tape file directly (so live, replayed and offline agree exactly).
#pragma once

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "fralab/analyze/pair_analyzer.h"
#include "fralab/core/in_order.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/tape_file.h"

namespace fralab {

/// Feeds tape records to a set of pair analysers. Records of another run id are ignored once the
/// run id is known (the first record fixes it unless one is given). Tape blocks (by seq, from 0)
/// and status events (by seq, from 0; the start event, seq -1, passes at once) reach the analysers
/// in sequence order, each once: a duplicate is dropped, a block or event that arrives early is
/// held until the gap before it is filled (a retransmission), so the numbers never depend on the
/// order datagrams arrived or were recorded in. flush() gives up on gaps still open (the end of a
/// tape): what follows them is delivered and the windows they cut are reported invalid.
class TapeFeeder {
 public:
  TapeFeeder(const std::vector<std::string>& pairs, const AnalyzerOptions& opt,
             std::string run_id = "");
  enum class Kind { kOther, kTape, kStatus };
  struct Fed {
    Kind kind = Kind::kOther;  // kOther: another channel or another run
    bool duplicate = false;
  };
  /// Decodes and dispatches one record; InputError names the channel for a wrong message type.
  Fed feed(const std::string& channel, const void* data, int size);
  /// The last tape block / status event delivered without a gap (-1: none): what a live analyser
  /// acknowledges.
  int64_t tape_delivered() const { return tape_.delivered(); }
  int64_t status_delivered() const { return status_.delivered(); }
  std::vector<std::unique_ptr<PairAnalyzer>>& analyzers() { return an_; }
  /// The run's final tape block has arrived and every analyser has resolved its windows.
  bool all_done() const;
  /// Delivers everything held (gaps given up) and resolves every pending window. Returns the
  /// number of tape blocks and status events given up.
  int64_t flush();
  const std::string& run_id() const { return run_id_; }
  /// Tape blocks refused because their checksum failed (fralab/lcm/codec.h CorruptBlock), by seq.
  const std::set<int64_t>& corrupt() const { return corrupt_; }

 private:
  void deliver();
  std::vector<std::unique_ptr<PairAnalyzer>> an_;
  std::string run_id_;
  InOrder<Block> tape_{0};
  InOrder<StatusEvent> status_{0};
  std::set<int64_t> corrupt_;
  bool final_seen_ = false;
};

/// Offline tape mode: every pair over the whole tape file, flushed at the end (blocks recorded out
/// of order after a retransmission are put back in order; blocks the tape never got make invalid
/// points naming the gap).
std::vector<Frd> analyze_tape_file(const std::string& path, const std::vector<std::string>& pairs,
                                   const AnalyzerOptions& opt);

}  // namespace fralab
