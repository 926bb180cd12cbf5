// DIR/run.json as typed records, the contract of docs/formats.md §13: RunRecord, the record of one
// `fralab measure` run ("format": "fralab-run/1"), and AutoRunRecord, that of an auto campaign
// (`--excitation auto`: DIR/run.json beside DIR/multisine/ and DIR/sine/, each a RunRecord's
// folder). Every place that writes or reads run.json goes through these: the run's driver
// (lab/src/measure_run.cc), the auto campaign (auto_campaign.h), measure() telling the two apart
// on --resume, the diagnosis reading the measurement chain, `fralab run` printing the times.
//
// The JSON is nlohmann's default (keys sorted), written with json_save_file. A key a record may
// lack is a std::optional here, absent from the file when empty. Reading refuses a missing or
// malformed key with an InputError "FILE: /PATH/KEY: what is wrong"; a key this version does not
// know (a newer fralab's) is kept, with its value as read, and written back as long as the object
// that held it is written (`unknown`).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "fralab/acquire/campaign.h"
#include "fralab/core/json_util.h"
#include "fralab/core/measurement_chain.h"
#include "fralab/exchange/data_quality.h"

namespace fralab {

/// run.json's "state": "running" (written when the run starts), "complete", "partial"
/// (everything measured, a later step failed: failed_step), "failed" or "interrupted" (reason).
/// An auto campaign's is "complete" or "partial".
enum class RunRecordState { kRunning, kComplete, kPartial, kFailed, kInterrupted };
const char* to_string(RunRecordState s);

/// "failed_step": the step after measuring that failed ("identify": the fits, transfer matrix or
/// state model) and its one-line error. The tape and frd files are complete; --resume fits again.
struct FailedStep {
  std::string step;
  std::string error;
  bool operator==(const FailedStep&) const = default;
};

/// What both records say of how the run stands.
struct RunOutcome {
  RunRecordState state = RunRecordState::kRunning;  // "state"
  std::optional<std::string> reason;                // "reason": failed or interrupted, why
  std::optional<FailedStep> failed_step;            // "failed_step": partial
  std::optional<int> resumed;                       // "resumed": times resumed (absent: never)
};

/// "options" of a fralab-run/1 record: what a resume needs besides DIR/engine.json and the tape.
/// The keys a record may lack are those of runs recorded before they were (a resume then takes
/// MeasureOptions' defaults).
struct RunOptions {
  uint64_t seed = 1;               // "seed": the plant's noise seed
  bool no_noise = false;           // "no_noise"
  std::string fit_delay = "auto";  // "fit_delay": identify's --delay
  std::optional<bool> fit;  // "fit": false when the run fits nothing (an auto campaign's runs)
  std::optional<double> timeout_s;                          // "timeout_s", s
  std::optional<double> stall_timeout_s;                    // "stall_timeout_s", s
  std::optional<std::map<std::string, std::string>> hosts;  // "hosts": process kind -> deputy
  std::optional<std::string> deputy_url;                    // "deputy_url" ("" the default)
  std::vector<std::string> acquire_flags;  // "acquire_flags": acquire_flags() of the acquisition
};

/// DIR/run.json of `fralab measure` (docs/formats.md §13), written when the run starts (state
/// running, with what a resume needs) and again when it ends. Times are seconds.
struct RunRecord : RunOutcome {
  static constexpr const char* kFormat = "fralab-run/1";
  std::string run_id;              // "run_id": every LCM message of the run begins with it
  std::string engine;              // "engine": the model's name
  std::string inputs;              // "inputs": those excited, "NAME,NAME"
  std::vector<std::string> pairs;  // "pairs": per input X, X:O for every output O, u_X:X, u_X:O
  RunOptions options;              // "options"
  /// "measurement_chain" (docs/formats.md §12): the lab's, as on the tape's start event.
  std::optional<MeasurementChain> measurement_chain;
  std::string lcm_url;  // "lcm_url": the run's data URL (its control URL: port + 1)
  // Written when the run ends (a resumed run's are its last ending's until then):
  std::optional<double> engine_time_s;  // "engine_time_s": engine (sample-clock) time, s
  std::optional<double> wall_time_s;    // "wall_time_s": acquisition and analysis, s
  std::optional<double> speedup;        // "speedup": engine time over wall time
  std::optional<int64_t> tape_blocks;   // "tape_blocks": tape blocks on the tape
  std::optional<double> fit_time_s;     // "fit_time_s": the identifier after the analysers, s
  /// "retransmissions", "items_retransmitted": requests, and the blocks and events they resent
  /// (from DIR/acquire.json, when the acquisition wrote it).
  std::optional<int64_t> retransmissions, items_retransmitted;
  /// "adaptive": the adaptive stepped sine's steps and the count of each state, as
  /// adaptive_steps_json (acquire/adaptive_sine.h) writes them for acquire.json too; kept as
  /// that JSON.
  std::optional<Json> adaptive;
  /// "data_quality": the tape's checks (exchange/data_quality.h), written when the run ends;
  /// absent in runs recorded before them.
  std::optional<DataQuality> data_quality;
  /// "zoom": where a multisine's zoomed modes (--zoom) got their lines, one object per mode in
  /// the band: "wn_rad_s", "zeta", "lines_in_band", "lines_in_reach", "resolution_hz", "zoomed",
  /// "period_needed_s" (acquire/campaign.h: ZoomPlacement); absent without a zoom.
  std::vector<ZoomPlacement> zoom;
  /// Members this version does not know: JSON pointer (in the file) -> value as read.
  Json unknown = Json::object();
};

/// One input of an auto campaign ("inputs"."X").
struct AutoRunInput {
  double nl_rel_median = -1;  // "nl_rel_median": its actuator curve's distortion, -1 when none
  std::string measured_by;    // "measured_by": "multisine" or "sine"
};

/// DIR/run.json of an auto campaign (docs/formats.md §13: "excitation": "auto"), written when
/// the campaign ends and again when `fralab measure --resume DIR` fits a partial one again.
struct AutoRunRecord : RunOutcome {
  /// "fit_delay": identify's --delay (absent in campaigns recorded before it was: "auto").
  std::optional<std::string> fit_delay;
  std::string engine;        // "engine": the model's name
  uint64_t seed = 1;         // "seed": the multisine's noise seed (the sine's is +1000)
  double engine_time_s = 0;  // "engine_time_s": both runs', s
  double wall_time_s = 0;    // "wall_time_s": both runs', s
  double speedup = 0;        // "speedup": engine time over wall time
  struct Multisine {
    std::string dir;           // "dir": its folder (a RunRecord's)
    double engine_time_s = 0;  // "engine_time_s", s
  } multisine;                 // "multisine"
  struct Sine {
    std::string dir;                           // "dir": its folder (a RunRecord's, when it ran)
    double engine_time_s = 0;                  // "engine_time_s", s (0: no sine)
    std::vector<std::string> inputs;           // "inputs": the inputs measured by sine
  } sine;                                      // "sine"
  std::map<std::string, AutoRunInput> inputs;  // "inputs": per input name
  double nl_threshold = 0;  // "nl_threshold": nl_rel_median above it is measured by sine
  /// "measurement_chain" (docs/formats.md §12), the multisine run's.
  std::optional<MeasurementChain> measurement_chain;
  std::vector<std::string> pairs;  // "pairs": the merged curves' pairs, sorted
  /// Members this version does not know: JSON pointer (in the file) -> value as read.
  Json unknown = Json::object();
};

/// The records as JSON (and the unknown members put back) and back; `file` names the source in
/// errors.
Json run_record_to_json(const RunRecord& r);
RunRecord run_record_from_json(const Json& j, const std::string& file);
Json auto_run_record_to_json(const AutoRunRecord& r);
AutoRunRecord auto_run_record_from_json(const Json& j, const std::string& file);

/// DIR/run.json of either kind: an auto campaign's when its "excitation" is "auto".
using AnyRunRecord = std::variant<RunRecord, AutoRunRecord>;
AnyRunRecord load_any_run_record(const std::string& file);
/// A fralab-run/1 record; InputError naming the file for an auto campaign's.
RunRecord load_run_record(const std::string& file);
/// An auto campaign's record; InputError naming the file for another.
AutoRunRecord load_auto_run_record(const std::string& file);
void save_run_record(const std::string& file, const RunRecord& r);
void save_run_record(const std::string& file, const AutoRunRecord& r);

}  // namespace fralab
