// The two-channel servoanalyser for one pair E1:E2, fed with the tape's records in any order.
//
// Input: tape blocks (any subset of channels; E1 and E2 must be among them) and excitation status
// events. Each "integrate" status defines a window [sample, sample + n_samples) of whole reference
// cycles (a stepped sine: reference from the status's phase and frequency; a sweep: the tape's
// per-sample ref_phase channel); when both channels cover it, the window gives one point:
//   ratio R = P2 / P1 (fourier_filter.h), w = 2 pi f, mag = |R|, phase_deg = arg R in degrees;
//   sigma: the window is cut into K = min(8, n_cycles) blocks after removing each channel's window
//          mean; with block phasors p1_b, p2_b and residuals e_b = p2_b - R p1_b,
//          sigma = sqrt(sum |e_b|^2 / (K (K - 1))) / |P1| (the standard deviation of R);
//   coherence = |sum conj(p1_b) p2_b|^2 / (sum |p1_b|^2 sum |p2_b|^2);
//   h2_rel, h3_rel: E2's 2nd and 3rd harmonic amplitudes over its fundamental.
// Multisine windows ("multisine": whole periods of period_samples) give one point per excited line
// of the pair's input (the input named by E1 or E2; every line for two outputs): each period is
// transformed (FFTW), R(k) = mean_p X2_p(k) / mean_p X1_p(k), sigma from the spread over periods
// of z_p = X2_p - R X1_p (as over blocks above) pooled over line k and the nearest line no input
// excites each side (z about its mean there: noise only, three times the degrees of freedom of a
// few periods), coherence from line k's spread, and nl_rel = the mean level of E2 on those
// nearest non-excited lines, relative to |X2(k)| (the best linear approximation's
// nonlinear-distortion sign).
// Orthogonal multisines (a line listed for several inputs: every excited input on every line, n_u
// experiments with step = r n_u + e, acquire/campaign.h): each experiment's window is transformed
// per period as above, together with the commands of the n_u inputs (tape channels u_<input>, the
// references); once the n_u experiments of realisation r are in, per line k with the input matrix
// U (U_qe = mean-period spectrum of input q's command in experiment e) and the channels' mean
// spectra X_e, the responses to each reference are h = X U^{-1} (a row per channel), and
//   R = h2_q / h1_q (q the pair's input: exactly what a stepped sine of input q alone measures,
//       P3-coupled fuel measurement and all). For a pair X:O (E1 an input's position), an input
//       whose position distorts (AnalyzerOptions::distortion_threshold: a backlash at the
//       multisine's level) enters U by its measured position instead of its command: its
//       distortion is not a linear function of the references and would otherwise leak into every
//       other input's estimate; the paths after the position are linear, so its own X:O is then
//       exact (O's coefficient on X's position);
//   sigma^2 = sum_e |U^{-1}_eq|^2 [var(mean_p z_ep) + sum_r |h2_r - R h1_r|^2 var(U_re)]
//       / |h1_q|^2, z_ep = X2_ep - R X1_ep per period (the linearised error of h2_q - R h1_q,
//       with the channels' covariance), the variance of the period mean pooled over line k and
//       the nearest non-excited line each side (the same z there: noise only, a periodic
//       distortion cancels in the spread), three times the degrees of freedom of a few periods;
//       r over the inputs that enter U by their measured position, var(U_re) that position's
//       period-mean variance pooled the same way (its sensor noise is in the regressor, an error
//       in every input's estimate that neither channel of the pair carries: at the J85's 95 %
//       the A8 position's noise put IGV -> P5, a path the engine does not have, 2-5 sigma from
//       zero over 0.4-8 Hz);
//   coherence = |R|^2 / (|R|^2 + n_u M sigma^2) (a single-input measurement's over the same
//       n_u M periods with that sigma); nl_rel = the mean over experiments of the level of E2 on
//       the nearest non-excited lines relative to |X2(k)|.
// Points carry step = r n_u and line_amplitude, the input's command amplitude on the line (the
// mean over experiments of 2 |U_qe| / P; a zippered or one-input multisine: for pairs u_X:E2).
// Several random-phase realisations of the same multisine (either design) are combined in frd()
// into the best linear approximation per line, sigma split into its noise and stochastic
// nonlinear parts (analyze/bla.h); one realisation's points are returned as they are. The
// commands and positions are kept from the design's first status on (blocks before it keep E1
// and E2 only). An experiment that is invalid (gaps, no command or
// position channel, a status stating another design) makes its realisation's points invalid with
// its note; a realisation whose experiments never all arrive gives one invalid point at flush().
// Arithmetic depends only on the samples and the status, never on arrival order or timing, so
// live, replayed and offline analyses give identical numbers. A window with a missing sample
// (lost or never-arrived block) yields a point with valid = false and a note naming the gap; so
// does a window, or the settle before it, with a sample a free-running plant held because its
// command buffer ran dry (tape channel "underrun" nonzero: plant/command_buffer.h), the
// acquisition then repeating the step.
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
