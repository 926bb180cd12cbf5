// AcquireOptions at the edges, in one place: the flags that set them (fralab-acquire, and fralab
// measure/run/diagnose, which pass them on), the flags that reproduce them exactly (numbers written
// losslessly) for a child process, and their JSON form (docs/formats.md §27). All three are driven
// by one table, acquire_fields(): a field of AcquireOptions is a row of it, so it cannot be bound
// to a flag and then dropped between processes (tests/unit/acquire/acquire_flags_test.cc holds
// every row to the round trip, and the table to the struct's member count).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "fralab/acquire/acquisition.h"
#include "fralab/core/json_util.h"

namespace fralab {

/// One field of AcquireOptions: its flag, its JSON key, and how it is bound, written as argv words
/// and written to and read from JSON.
struct AcquireField {
  /// When acquire_flags writes the field. The argv lists the groups in this order (the
  /// unconditional fields first), each group's fields in the table's order: the order run.json's
  /// options.acquire_flags has always had.
  enum class Written {
    kAlways,
    kIfOddLines,         // --odd-lines: only when set
    kIfFreeRunning,      // --free-running, --lead, --max-repeats: a free-running plant only
    kIfInputs,           // --input: only when it names inputs ("" is every input)
    kIfAdaptive,         // --sigma-target, --pilot-cycles: the adaptive stepped sine only
    kIfAdaptiveDecided,  // --adaptive-decided: adaptive, with decisions taken
    kIfZoom,             // --zoom, --zoom-period-factor: modes to zoom on
  };
  std::string flag;  // "--band"
  std::string key;   // JSON pointer in acquire_options_to_json's object: "/band"
  Written written = Written::kAlways;
  /// Adds the flag to `app`, bound to `o` (its help text, default and check).
  std::function<void(CLI::App* app, AcquireOptions& o, bool* auto_campaign)> bind;
  /// The words after the flag in acquire_flags (none for a switch such as --odd-lines).
  std::function<std::vector<std::string>(const AcquireOptions& o)> words;
  std::function<Json(const AcquireOptions& o)> to_json;
  /// Sets the field from `v`; InputError naming `where` when `v` is not a value of it.
  std::function<void(AcquireOptions& o, const Json& v, const JsonWhere& where)> from_json;
};

/// Every field of AcquireOptions (AdaptiveSineOptions's two counted as two), in the order the
/// flags are added (that of --help).
const std::vector<AcquireField>& acquire_fields();

/// Whether acquire_flags writes a field of group `w` for options `o`.
bool written_for(AcquireField::Written w, const AcquireOptions& o);

/// Adds --input, --band, --excitation, --multisine-phases, --odd-lines, --multisine-design,
/// --realisations, --points-per-decade, --amplitude-pct, --amplitude-scale, --min-cycles,
/// --min-integrate-s, --settle-cycles, --sample-rate, --speed, --block, --window,
/// --settle-time-constant-s, --free-running, --lead, --max-repeats, --sigma-target,
/// --pilot-cycles, --adaptive-decided, --zoom, --zoom-period-factor, bound to `o`.
/// With `auto_campaign`, --excitation also takes "auto" (the lab's campaign that decides itself,
/// lab/auto_campaign.h), which sets *auto_campaign (and o.excitation to multisine).
void add_acquire_flags(CLI::App* app, AcquireOptions& o, bool* auto_campaign = nullptr);

/// The flags that make add_acquire_flags reproduce `o` exactly. A group's fields (--lead with
/// --free-running, --pilot-cycles with --sigma-target, ...) are left out when the group is off:
/// they do nothing then.
std::vector<std::string> acquire_flags(const AcquireOptions& o);

/// The options as one JSON object (docs/formats.md §27): every field, by its key (adaptive's
/// under "adaptive"), numbers as JSON numbers (which nlohmann writes and reads back exactly), the
/// excitation and multisine design as their flag words.
Json acquire_options_to_json(const AcquireOptions& o);
/// Back: a key left out keeps its default; a value of the wrong kind, or a key that is not a
/// field, is an InputError naming `where` and the key.
AcquireOptions acquire_options_from_json(const Json& j, const JsonWhere& where);

}  // namespace fralab
