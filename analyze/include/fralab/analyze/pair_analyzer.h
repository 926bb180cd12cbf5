// The two-channel servoanalyser for one pair E1:E2 (E2 relative to E1), fed with the tape's
// records in any order: tape blocks (any subset of channels, E1 and E2 among them) and excitation
// status events. Each "integrate" window [sample, sample + n_samples) of whole reference cycles
// (stepped sine: the status's phase and frequency; sweep: the tape's ref_phase) gives one point:
//   R = P2 / P1 (fourier_filter.h), w = 2 pi f (rad/s, f in Hz), mag = |R|, phase_deg = arg R
//   in degrees (positive: E2 leads E1); with K = min(8, n_cycles) blocks' phasors p1_b, p2_b,
//   sigma = sqrt(sum_b |p2_b - R p1_b|^2 / (K (K - 1))) / |P1| (the standard deviation of R),
//   coherence = |sum conj(p1_b) p2_b|^2 / (sum |p1_b|^2 sum |p2_b|^2), h2_rel and h3_rel E2's
//   2nd and 3rd harmonic amplitudes over its fundamental.
// A multisine window gives one point per excited line k of the pair's input, over its periods
//   R(k) = mean_p X2_p(k) / mean_p X1_p(k), sigma from the spread of X2_p - R X1_p pooled with the
//   nearest non-excited lines, nl_rel = E2's level there over |X2(k)|; an orthogonal multisine's
//   n_u experiments are solved per line, h = X U^{-1} (U the commands' spectra), R = h2_q / h1_q
//   (q the pair's input), with line_amplitude. frd() combines realisations into the best linear
// approximation (analyze/bla.h). Numbers depend only on the samples and status events, never on
// arrival order or timing. A window with a missing sample, or with a sample the plant held in it
// or in its settle (tape channel "underrun" nonzero), an invalid experiment and a realisation
// never completed give points with valid = false and a note naming the cause.
// Method: docs/method/analyser.md ("Conventions", "The Fourier filter", "Periodic multisines").
#pragma once

#include <complex>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fralab/analyze/sample_store.h"
#include "fralab/core/block.h"
#include "fralab/core/frd.h"

namespace fralab {

namespace analyze_detail {
class OrthogonalRealisations;
}

struct AnalyzerOptions {
  int max_blocks = 8;  // K for sigma/coherence, >= 2
  /// A window still missing samples when data this many samples beyond its end has arrived is
  /// declared invalid (allows reordering up to that distance).
  int64_t reorder_slack_samples = 5000;
  /// Orthogonal multisines: an input whose position distorts beyond this (the median over lines of
  /// its level on the nearest non-excited lines relative to the line) is, for pairs X:O, a
  /// regressor by its measured position instead of its command (its distortion otherwise leaks
  /// into every other input's estimate).
  double distortion_threshold = 0.01;
  /// Only analyse steps exciting this input. "" (default): a step is analysed unless E1 or E2 is
  /// an input channel (or its command u_<input>) that the step does not excite; a pair of two
  /// outputs is analysed at every step. Status events list every plant input, amplitude 0 when
  /// not excited.
  std::string input;
  void validate() const;
};

class PairAnalyzer {
 public:
  /// `store`: the samples, shared with the other analysers of the same tape stream (each block
  /// given to every one of them, in the same order: TapeFeeder); nullptr: its own.
  PairAnalyzer(const std::string& pair, const AnalyzerOptions& options = {},
               std::shared_ptr<SampleStore> store = nullptr);
  ~PairAnalyzer();
  PairAnalyzer(const PairAnalyzer&) = delete;
  PairAnalyzer& operator=(const PairAnalyzer&) = delete;

  void on_status(const StatusEvent& status);
  void on_block(const Block& block);
  /// Tape block `seq` arrived corrupt (failed its checksum) and was refused: a window it cuts
  /// says so in its note.
  void note_corrupt(int64_t seq) { corrupt_.insert(seq); }
  /// Points completed since the last call, in completion order.
  std::vector<FrdPoint> take_new_points();
  /// Every point so far (ascending w), as a fralab-frd/1 document.
  Frd frd() const;
  /// True once a "done" status arrived and every window before it has been resolved.
  bool done() const { return done_seen_ && pending_.empty(); }
  /// Resolves every pending window now (end of a tape): missing samples make invalid points.
  void flush();
  const std::string& pair() const { return pair_; }
  std::string e1() const { return e1_; }
  std::string e2() const { return e2_; }
  int64_t blocks_seen() const { return blocks_seen_; }

 private:
  struct Window {
    StatusEvent st;
    int64_t from = 0;      // the step's settle start (held samples there disturb the window too)
    std::vector<int> ins;  // an orthogonal multisine's inputs (indices into st.inputs); else empty
  };
  void try_complete(bool force);
  FrdPoint compute(const Window& w);
  std::vector<FrdPoint> compute_multisine(const Window& w);
  bool covers(int64_t a, int64_t b) const;
  std::string describe_gaps(int64_t a, int64_t b) const;
  bool wants(const StatusEvent& st) const;
  void trim();

  std::string pair_, e1_, e2_;
  AnalyzerOptions opt_;
  std::map<int64_t, Window> pending_;  // by start sample
  std::vector<FrdPoint> points_, fresh_;
  std::vector<FrdPoint> realisation_points_;  // a multisine's, each realisation's (frd(): BLA)
  // The samples: E1, E2, the tape's ref_phase (NaN when absent) and the channels an orthogonal
  // multisine needs besides (the commands u_X and positions X of its inputs, kept from its status
  // on), possibly shared with other pairs; this pair is reader `reader_` of it.
  std::shared_ptr<SampleStore> store_;
  int reader_ = 0;
  /// Channel `ch` from sample n (n >= store_->base(); the channel kept).
  const double* samples(const std::string& ch, int64_t n) const;
  /// The channel's samples over status st's window (nullptr where the store lacks it, it does
  /// not cover the window, or it holds a NaN there).
  std::function<const double*(const std::string&)> window_channel(const StatusEvent& st) const;
  // The orthogonal multisines' realisations until their experiments are in.
  std::unique_ptr<analyze_detail::OrthogonalRealisations> orthogonal_;
  // Samples a free-running plant held (tape channel "underrun"), and the last settle status (its
  // step and start sample).
  HeldSamples held_;
  int settle_step_ = -1;
  int64_t settle_from_ = 0;
  int64_t max_seen_ = -1;
  int64_t blocks_seen_ = 0;
  std::map<int64_t, std::pair<int64_t, int64_t>> seqs_;  // seq -> [start, end)
  std::set<int64_t> corrupt_;
  bool done_seen_ = false;
  int64_t done_sample_ = 0;
};

/// Every pair over a whole run held in memory (offline: a mended series re-cut into blocks), one
/// sample store for all: the status events (seq >= 0; the start and abort events define no
/// window) then the blocks in order, flushed at the end. The same numbers as the tape's analysis.
std::vector<Frd> analyse_run_in_memory(const std::vector<StatusEvent>& events,
                                       const std::vector<Block>& blocks,
                                       const std::vector<std::string>& pairs,
                                       const AnalyzerOptions& options = {});

}  // namespace fralab
