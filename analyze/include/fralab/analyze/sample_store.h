// The samples the pair analysers of one tape stream keep, stored once for all of them: each
// channel any of them needs (its two channels, the reference phase, an orthogonal multisine's
// commands and positions) is one array from a common first sample, however many pairs read it.
// A grouped analyser (one process for an input's pairs, or N pairs) thus copies and holds a block's
// channels once, not once per pair: 4 inputs x 16 outputs held 33 pairs x 7 channels per
// analyser before, 22 channels now.
//
// Samples are indexed by their sample number n (the block's start_sample + k); stored from base()
// to end() - 1; a sample no block has brought reads NaN and have(n) is false. Memory is released
// from the front when every reader has said it no longer needs it (release()).
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "fralab/core/block.h"

namespace fralab {

class SampleStore {
 public:
  /// Keep `channel` from now on; samples stored before read NaN (as do samples of a block that
  /// lacks the channel).
  void keep(const std::string& channel);
  /// Stores block b's kept channels. The first block fixes base(): its start, or `slack` samples
  /// before it when it starts later than 2 x slack (a reader joining a run late does not hold the
  /// hours before it). A block already stored (its seq) is not stored again: false. The caller
  /// refuses blocks far from what is stored (PairAnalyzer::on_block: a corrupt record), so that
  /// start_sample + n_samples and the arrays' growth stay bounded.
  bool add(const Block& b, int64_t slack);
  bool empty() const { return have_.empty(); }
  int64_t base() const { return base_; }
  int64_t end() const { return base_ + int64_t(have_.size()); }
  bool have(int64_t n) const { return n >= base_ && n < end() && have_[size_t(n - base_)]; }
  /// The kept channel's samples from base(), nullptr when it is not kept.
  const std::vector<double>* channel(const std::string& name) const;

  /// A reader's handle for release().
  int add_reader();
  void remove_reader(int reader);
  /// Reader `reader` needs nothing before sample `keep`. The front is dropped when every reader
  /// has released at least 65536 samples (65 s at 1 kHz) and at least as many as stay: each sample
  /// is then moved a bounded number of times, and the store holds at most about twice what its
  /// readers need.
  void release(int reader, int64_t keep);

 private:
  int64_t base_ = 0;
  std::map<std::string, std::vector<double>> ch_;
  std::vector<char> have_;
  std::set<int64_t> seqs_;       // blocks stored, by seq
  std::map<int, int64_t> keep_;  // per reader: samples it still needs from here on
  int next_reader_ = 0;
};

}  // namespace fralab
