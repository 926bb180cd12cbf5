// The acquisition's protocol logic, free of LCM: which campaign a set of options asks for, the
// command block of each sequence number (what fralab-acquire publishes on FRALAB_CMD), and the
// flow-control bookkeeping of acknowledgements. fralab-acquire wires these to LCM; the tests'
// generators (tests/util) call the same functions, so a simulated tape is the lab's tape.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fralab/acquire/adaptive_sine.h"
#include "fralab/acquire/campaign.h"
#include "fralab/core/block.h"
#include "fralab/plant/model.h"

namespace fralab {

/// "stepped", "sweep", "multisine" (the flag's words; Excitation is core/block.h's).
const char* to_string(Excitation e);
/// InputError naming the text otherwise.
Excitation excitation_from_string(const std::string& s);

/// One acquisition: the excitation and its schedule, the amplitudes, the block size and the flow
/// control. Frequencies Hz, amplitudes % of full scale, times s. A field added here is a row of
/// acquire_fields() (acquire/acquire_flags.h), its flag and JSON key; acquire_flags_test fails
/// until it is.
struct AcquireOptions {
  std::string inputs;             // "NAME[,NAME...]" to excite; "" = every input
  std::string band = "0.04:100";  // LO_HZ:HI_HZ
  Excitation excitation = Excitation::kStepped;
  std::string multisine_phases = "low-crest";  // "schroeder", "random" or "low-crest"
  bool odd_lines = false;                      // multisine: odd harmonics only
  // multisine: every input on every line in n_u experiments (orthogonal) or disjoint lines in one
  // (zippered); realisations: independent random-phase realisations of the orthogonal design.
  MultisineOptions::Design multisine_design = MultisineOptions::Design::kOrthogonal;
  int realisations = 1;
  int points_per_decade = 10;
  double amplitude_pct = -1;     // < 0: each input's test_amplitude_pct, else 2
  double amplitude_scale = 1.0;  // multiplies every input's amplitude
  int min_cycles = 8;            // stepped/sweep: cycles per point; multisine: periods (>= 2)
  double min_integrate_s = 4.0;
  double settle_cycles = 1.0;  // stepped sine: settle at least this many cycles per step
  double sample_rate_hz = 1000.0;
  double slowest_time_constant_s = -1;  // settling; < 0: the model's slowest (largest 1/|pole|)
  // Samples per command (and tape) block; 0: sized by block_samples (half a second of samples, at
  // most what keeps a tape block under 60 kB). Results do not depend on it: only the messages'
  // count does, and with it the lab's speed.
  int block = 0;
  int window = 2;    // blocks in flight ahead of the slowest consumer
  double speed = 0;  // 1 = real time, 0 = as fast as the consumers keep up
  // A free-running plant: it runs on its own clock at `speed` (> 0) x real time,
  // playing commands from a buffer; the acquisition keeps `lead` blocks of commands ahead of the
  // plant's clock (no acknowledgement awaited), watches the tape for held samples (channel
  // "underrun") and repeats each step they touch, at most `max_repeats` rounds.
  bool free_running = false;
  int lead = 10;
  int max_repeats = 3;
  // Stepped sine, adaptive (acquire/adaptive_sine.h) when adaptive.sigma_target > 0: pilot
  // windows of adaptive.pilot_cycles (min_cycles and min_integrate_s then do not apply), each step
  // extended while running until its sigma / |G| meets the target or its limit. adaptive_decided:
  // the extensions a resumed run took before (parse_decisions' text).
  AdaptiveSineOptions adaptive;
  std::string adaptive_decided;
  // Multisine: lightly damped modes to resolve and how far the period may grow for them
  // (MultisineOptions::zoom, zoom_period_factor).
  std::vector<ZoomMode> zoom;
  double zoom_period_factor = 1.0;
  /// InputError naming the option (block, window, speed, band, excitation settings).
  void validate() const;
  /// Every field equal (the flags' and JSON form's round trips are held to it).
  bool operator==(const AcquireOptions&) const = default;
};

/// The stepped-sine plan's options (band, density, cycles, settle) on model `m`.
SteppedSineOptions stepped_sine_options(const Model& m, const AcquireOptions& o);

/// The multisine's options (band, density, periods, settle, design, zoom) on model `m`.
MultisineOptions multisine_options(const Model& m, const AcquireOptions& o);

/// Where a multisine's zoomed modes got their lines (empty for another excitation or no zoom).
std::vector<ZoomPlacement> zoom_placement(const Model& m, const AcquireOptions& o);

/// The campaign the options describe on model `m` (the plan of steps, sweep or multisine).
std::unique_ptr<Campaign> make_campaign(const Model& m, const AcquireOptions& o,
                                        const std::string& run_id);

/// The decisions of an adaptive stepped sine (acquire/adaptive_sine.h) on the campaign
/// make_campaign made for `o`, on the tape of model `m`'s outputs; steps starting before
/// `first_sample` (a resumed run) are taken. nullptr when the campaign is not adaptive.
std::unique_ptr<AutoIntegrator> make_auto_integrator(Campaign& c, const Model& m,
                                                     const AcquireOptions& o,
                                                     int64_t first_sample = 0);

/// The largest tape block, bytes: LCM 1.3.1 loses a fragmented message whose fragments arrive out
/// of order (docs/lcm-protocol.md), so a block stays under one datagram.
inline constexpr double kMaxTapeBlockBytes = 60000;

/// Samples per block of a run of `o` on model `m`: o.block when > 0 (InputError, naming --block,
/// when its tape block, 8 bytes a sample on 2 n_inputs + n_outputs + 2 channels, would exceed
/// kMaxTapeBlockBytes); for 0, half a second of samples at o.sample_rate_hz, at most what keeps
/// the tape block under that size, at least 1. A tape block is what every consumer decodes and
/// acknowledges, so its size sets the messages per second of engine time: 100 samples a block
/// ran the J85 stepped lab at 186x real time, 500 at 284x (docs/validation.md).
int block_samples(const Model& m, const AcquireOptions& o);

/// InputError naming `what` unless block >= 1: a block of 0 (--block's "sized") goes through
/// block_samples before anything counts or cuts samples by it.
void require_sized_block(int block, const std::string& what);

/// Number of command blocks of `block` samples (>= 1, a sized block; InputError otherwise) that
/// carry the whole campaign.
int64_t command_block_count(const Campaign& c, int block);

/// The block that ends an aborted run: `n` samples from `start_sample` of every input's command
/// held at its operating point (its dc), the reference zero, final_block set.
Block abort_block(const Campaign& c, int64_t seq, int64_t start_sample, int n,
                  double sample_rate_hz, const std::string& run_id);

/// Command block `seq`: samples [seq * block, ...) of every input's command (channels u_<input>)
/// and the reference (ref_phase, rad; ref_freq_hz), final_block on the last one. block >= 1.
Block command_block(const Campaign& c, int64_t seq, int block, double sample_rate_hz,
                    const std::string& run_id);

}  // namespace fralab
