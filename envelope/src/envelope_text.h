// The envelope's numbers in its texts and reports: four significant digits.
#pragma once

#include <string>

#include "fralab/core/text.h"

namespace fralab::envelope_text {

inline std::string num(double v) { return significant(v, 4); }

}  // namespace fralab::envelope_text
