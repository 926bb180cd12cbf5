#include "fralab/core/pair_id.h"

#include "fralab/core/error.h"
#include "fralab/core/frd.h"

namespace fralab {

std::string command_channel(const std::string& input) { return "u_" + input; }

std::optional<std::string> commanded_input(const std::string& channel) {
  if (channel.rfind("u_", 0) != 0) return std::nullopt;
  return channel.substr(2);
}

PairId PairId::parse(const std::string& text) {
  const auto [e1, e2] = split_pair(text);
  PairId id;
  const std::optional<std::string> x = commanded_input(e1);
  id.command = x.has_value();
  id.input = x ? *x : e1;
  id.output = e2;
  if (id.input.empty() || id.output.empty())
    throw InputError("pair '" + text + "': an input and an output name are needed (E1:E2)");
  return id;
}

std::string PairId::str() const { return e1() + ":" + output; }

}  // namespace fralab
