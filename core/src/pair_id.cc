#include "fralab/core/pair_id.h"

#include "fralab/core/error.h"
#include "fralab/core/frd.h"

namespace fralab {

PairId PairId::parse(const std::string& text) {
  const auto [e1, e2] = split_pair(text);
  PairId id;
  id.command = e1.rfind("u_", 0) == 0;
  id.input = id.command ? e1.substr(2) : e1;
  id.output = e2;
  if (id.input.empty() || id.output.empty())
    throw InputError("pair '" + text + "': an input and an output name are needed (E1:E2)");
  return id;
}

std::string PairId::str() const { return (command ? "u_" : "") + input + ":" + output; }

}  // namespace fralab
