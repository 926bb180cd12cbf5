// Text at the edges: comma-separated lists (flags, CSV headers) and numbers written losslessly
// (flags passed to child processes, where std::to_string's 6 decimals would round).
#pragma once

#include <string>
#include <vector>

namespace fralab {

/// Splits on `sep`, dropping empty items: "a,b,,c" -> {"a", "b", "c"}.
std::vector<std::string> split_list(const std::string& text, char sep = ',');

/// The shortest decimal text that reads back as exactly `v` (std::to_chars round trip).
std::string lossless(double v);

}  // namespace fralab
