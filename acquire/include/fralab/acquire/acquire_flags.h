// AcquireOptions at the command-line edge, in one place: the flags that set them (fralab-acquire,
// and fralab measure/run/diagnose, which pass them on) and the flags that reproduce them exactly
// (numbers written losslessly) for a child process.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "fralab/acquire/acquisition.h"

namespace fralab {

/// Adds --input, --band, --excitation, --multisine-phases, --odd-lines, --points-per-decade,
/// --amplitude-pct, --amplitude-scale, --min-cycles, --min-integrate-s, --sample-rate, --speed,
/// --block, --window, --settle-time-constant-s, bound to `o`.
/// With `auto_campaign`, --excitation also takes "auto" (the lab's campaign that decides itself,
/// lab/auto_campaign.h), which sets *auto_campaign (and o.excitation to multisine).
void add_acquire_flags(CLI::App* app, AcquireOptions& o, bool* auto_campaign = nullptr);

/// The flags that make add_acquire_flags reproduce `o` exactly.
std::vector<std::string> acquire_flags(const AcquireOptions& o);

}  // namespace fralab
