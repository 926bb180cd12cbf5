// Text at the edges: comma-separated lists (flags, CSV headers) and numbers written losslessly
// (flags passed to child processes, where std::to_string's 6 decimals would round).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fralab {

/// Splits on `sep`, dropping empty items: "a,b,,c" -> {"a", "b", "c"}.
std::vector<std::string> split_list(const std::string& text, char sep = ',');
/// The items with `sep` between them: {"a", "b"} -> "a, b".
std::string join_list(const std::vector<std::string>& items, const std::string& sep = ", ");

/// The index of `name` in `names` (a block's or series' channels), -1 when absent.
inline int index_of(const std::vector<std::string>& names, const std::string& name) {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

/// Enums inside, words at the edges: the word of `e` in a table {{value, "word"}, ...} ("?" when
/// absent), and the value of a word (nullopt when absent).
template <class E, size_t N>
const char* enum_word(const std::pair<E, const char*> (&table)[N], E e) {
  for (const auto& [k, w] : table)
    if (k == e) return w;
  return "?";
}
template <class E, size_t N>
std::optional<E> enum_from_word(const std::pair<E, const char*> (&table)[N],
                                const std::string& word) {
  for (const auto& [k, w] : table)
    if (word == w) return k;
  return std::nullopt;
}

/// "A:B" (sep ':') as two numbers, each the whole of its side (std::stod's form); nullopt when the
/// text is not that.
std::optional<std::pair<double, double>> number_pair(const std::string& text, char sep = ':');

/// The shortest decimal text that reads back as exactly `v` (std::to_chars round trip).
std::string lossless(double v);

/// `v` to `digits` significant digits, as printf's %g writes it (reports and messages).
std::string significant(double v, int digits);

}  // namespace fralab
