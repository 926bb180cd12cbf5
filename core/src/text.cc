#include "fralab/core/text.h"

#include <charconv>
#include <cstdio>
#include <stdexcept>

namespace fralab {

std::string join_list(const std::vector<std::string>& items, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? sep : "") + items[i];
  return out;
}

std::vector<std::string> split_list(const std::string& s, char sep) {
  std::vector<std::string> out;
  size_t a = 0;
  while (a <= s.size()) {
    size_t b = s.find(sep, a);
    if (b == std::string::npos) b = s.size();
    if (b > a) out.push_back(s.substr(a, b - a));
    a = b + 1;
  }
  return out;
}

std::string lossless(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string significant(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::optional<std::pair<double, double>> number_pair(const std::string& text, char sep) {
  const size_t c = text.find(sep);
  if (c == std::string::npos) return std::nullopt;
  try {
    size_t p1 = 0, p2 = 0;
    const double a = std::stod(text.substr(0, c), &p1), b = std::stod(text.substr(c + 1), &p2);
    if (p1 != c || p2 != text.size() - c - 1) return std::nullopt;
    return std::pair{a, b};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

}  // namespace fralab
