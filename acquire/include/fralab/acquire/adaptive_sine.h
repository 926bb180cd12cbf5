// Adaptive stepped sine (`--sigma-target`): each point integrated until its
// sigma reaches a target or a cycle limit, decided while running, as a hardware analyser's
// auto-integration does. No I/O: fralab-acquire wires it to the tape (acquisition_node.h).
//
// The campaign (AdaptiveSineCampaign): the stepped sine's plan (acquire/campaign.h) with N1 =
// pilot_cycles cycles per step and no minimum integration time, each excited input through every
// step. Step g (0.. in test order) is its settle, its pilot window of N1 cycles (L samples), then
// the extensions decided so far: windows of c_j cycles (c_j a multiple of N1, c_j L / N1 samples:
// the same frequency, exactly), each an "integrate" status with the same step index, the sine
// continuing without a break; then the sine goes on to the next command block boundary (unused
// filler), where step g + 1's settle starts. So the samples before the end E of step g's last
// window never depend on what is decided at E, and the block holding sample E - 1 is the same
// whatever is decided: the acquisition publishes it, waits for the tape through E, and decides
// before the next block goes out (at most one block of filler a step). One block with every input
// at its operating point ends the run (so the last step is decided before the final block).
//
// The decision (AutoIntegrator, decide_step): after each window of step g the pairs of its input
// (X:O for every output O, and u_X:X) are analysed as the analysers do (pair_analyzer.h), each
// pair's windows of the step merged by inverse variance (analyze/repeats.h). With n the cycles
// integrated so far and s_p pair p's sigma / |G|, the noise of a Fourier filter's mean falls as
// 1 / sqrt(cycles), so p would reach s_p sqrt(n / limit) at the step's limit. A pair still above
// 1/3 there (|G| under 3 sigma: an absent path, or one buried in noise at this frequency) does
// not hold the step: however long it is integrated it measures nothing. With s the largest s_p
// of the pairs that hold it, the target t needs n (s / t)^2 cycles in all, and the step goes on
// for
//   c = N1 ceil((n (s / t)^2 - n) / N1) cycles, at most limit - n rounded down to whole N1,
// the limit being the fixed stepped sine's cycles at that step (max(min_cycles, ceil(
// min_integrate_s f)), acquire/campaign.h): every pair with a response gets the target or the
// fixed run's integration, an adaptive run never integrates a step longer than the fixed one
// would, and quiet steps stop early. c = 0 ends the step. Points that are invalid or carry no
// sigma do not count. Every decision depends on the tape's samples only, so a run, its replay and
// its resumption make the same decisions.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fralab/acquire/campaign.h"
#include "fralab/analyze/pair_analyzer.h"
#include "fralab/core/json_util.h"

namespace fralab {

struct AdaptiveSineOptions {
  double sigma_target = 0;  // relative: sigma / |G| on every pair of the input; 0: not adaptive
  int pilot_cycles = 4;     // N1: cycles of the first window, and the unit of extensions (>= 2)
  bool enabled() const { return sigma_target > 0; }
  /// InputError naming the option (a flag's name).
  void validate() const;
  bool operator==(const AdaptiveSineOptions&) const = default;
};

/// sigma / |G| beyond which a response is not told from zero (|G| < 3 sigma).
inline constexpr double kUndetectable = 1.0 / 3.0;

/// A step's decision after `cycles` integrated, from each pair's sigma / |G| (`rel_sigmas`, the
/// pairs with a usable point) and its cycle limit: the rule above.
struct StepDecision {
  int more = 0;           // cycles to go on for; 0: the step ends
  double worst = -1;      // largest sigma / |G| of the pairs that hold the step (-1: none)
  double worst_all = -1;  // ... of every pair
  int undetectable = 0;   // pairs whose |G| stays under 3 sigma even at the limit
  std::string state;      // when it ends: "met"; "limit" (short, no whole pilot left below its
                          // limit); "undetectable" (ended before its limit: no pair holds the
                          // step); "unusable" (no pair with a sigma)
};
StepDecision decide_step(int cycles, const std::vector<double>& rel_sigmas, int limit,
                         const AdaptiveSineOptions& o);

/// Decisions taken (what a resumed acquisition is given, AcquireOptions's adaptive_decided):
/// "G*C,G*C,...": step G extended by C cycles, in the order taken. InputError naming the token.
std::vector<std::pair<int, int>> parse_decisions(const std::string& text);
std::string format_decisions(const std::vector<std::pair<int, int>>& d);

/// A step of an adaptive run, as decided: its input, frequency, cycles and decision.
struct AdaptiveStep {
  std::string input;
  int step = 0;
  double f_hz = 0;
  int cycles = 0;
  StepDecision decision;
};

/// An adaptive run's steps from its curves (the analysers' points, a step's windows merged): per
/// step (FrdPoint::step) of input X, over the points of pairs X:O and u_X:X, with `limits` each
/// step's cycle limit (AdaptiveSineCampaign::limit), what AutoIntegrator decided on. In step order.
std::vector<AdaptiveStep> adaptive_steps(const std::vector<Frd>& curves, double sigma_target,
                                         const std::vector<int>& limits);

/// Steps as run.json and the acquisition's summary write them: {"steps": [...], and the count of
/// steps per state}.
Json adaptive_steps_json(const std::vector<AdaptiveStep>& steps);

class AdaptiveSineCampaign : public SegmentCampaign {
 public:
  /// `fixed`: the fixed stepped sine's plan (plan_stepped_sine), whose cycles are the limits;
  /// the pilot plan is the same band at pilot_cycles cycles a step (every step N1 cycles);
  /// `block`: the command block (samples); `decided`: extensions already taken.
  AdaptiveSineCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                       const SteppedSineOptions& fixed, int pilot_cycles, int block,
                       std::string run_id, const std::vector<std::pair<int, int>>& decided = {});
  int n_steps() const { return int(steps_.size()); }
  /// Step g's input (index into inputs()), frequency, pilot cycles and samples; its cycle limit.
  int input_of(int g) const { return steps_.at(size_t(g)).first; }
  const SineStep& step(int g) const { return steps_.at(size_t(g)).second; }
  int limit(int g) const { return limit_.at(size_t(g)); }
  /// The first sample of step g's settle (a command block boundary) and the end of its last window.
  int64_t step_start(int g) const { return start_.at(size_t(g)); }
  int64_t window_end(int g) const { return end_.at(size_t(g)); }
  /// Cycles step g integrates (pilot and extensions), and its extensions' cycles.
  int cycles(int g) const;
  const std::vector<int>& extensions(int g) const { return ext_.at(size_t(g)); }
  /// Step g goes on for `cycles` more (> 0, a multiple of its pilot's): everything before its
  /// current window_end is unchanged, what follows moves. InputError otherwise.
  void extend(int g, int cycles);
  const std::vector<std::pair<int, int>>& decisions() const { return decided_; }

 private:
  void build(const std::string& run_id);
  std::vector<std::pair<int, SineStep>> steps_;
  std::vector<int> limit_;
  std::vector<std::vector<int>> ext_;  // per step: extension cycles
  std::vector<std::pair<int, int>> decided_;
  std::vector<int64_t> start_, end_;
  int block_;
  std::string run_id_;
};

/// The decisions of an adaptive run, fed with its status events and tape blocks.
class AutoIntegrator {
 public:
  /// `outputs`: the model's outputs (the pairs X:O); steps starting before `first_sample` (a
  /// resumed run's first command block) are decided already.
  AutoIntegrator(AdaptiveSineCampaign& campaign, std::vector<std::string> outputs,
                 AdaptiveSineOptions o, int64_t first_sample = 0);
  ~AutoIntegrator();
  /// The end E of the window awaiting a decision: no command block starting at or after E goes
  /// out before decide() returned true. -1: nothing left to decide.
  int64_t decision_sample() const;
  /// The samples the pending decision needs, [its step's start, E).
  std::pair<int64_t, int64_t> needed_samples() const;
  /// A tape block (any order, duplicates ignored).
  void on_block(const Block& b);
  /// Takes the pending decision when every pair's point of the window is in (the campaign
  /// extended, or the step ended); false while tape is missing.
  bool decide();
  /// The steps decided so far.
  const std::vector<AdaptiveStep>& results() const { return results_; }

 private:
  void feed_events();
  AdaptiveSineCampaign& c_;
  std::vector<std::string> outputs_;
  AdaptiveSineOptions o_;
  int g_ = 0;                                      // the step being decided
  size_t fed_ = 0;                                 // campaign events given to the analysers
  std::vector<std::unique_ptr<PairAnalyzer>> an_;  // the step's pairs
  // per pair: the step's windows merged (analyze/repeats.h), and how many are in
  std::map<std::string, std::pair<Frd, size_t>> merged_;
  std::vector<AdaptiveStep> results_;
};

}  // namespace fralab
