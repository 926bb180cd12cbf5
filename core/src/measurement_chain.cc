#include "fralab/core/measurement_chain.h"

#include <cmath>

#include "fralab/core/pair_id.h"

namespace fralab {

std::complex<double> MeasurementChain::command_factor(double w) const {
  if (sample_rate_hz <= 0) return 1.0;
  const double x = w / (2 * sample_rate_hz);
  const double sinc = x == 0 ? 1.0 : std::sin(x) / x;
  std::complex<double> f = hold == Hold::kFirstOrder ? std::complex<double>(sinc * sinc, 0)
                                                     : sinc * std::exp(std::complex<double>(0, -x));
  if (converter_delay_s > 0) f *= std::exp(std::complex<double>(0, -w * converter_delay_s));
  return f;
}

std::complex<double> MeasurementChain::pair_factor(const std::string& e1, double w) const {
  if (commanded_input(e1)) return command_factor(w);
  for (const auto& x : reheld_inputs)
    if (x == e1) return command_factor(w);
  return 1.0;
}

std::complex<double> MeasurementChain::pair_factor(const PairId& pair, double w) const {
  if (pair.command) return command_factor(w);
  for (const auto& x : reheld_inputs)
    if (x == pair.input) return command_factor(w);
  return 1.0;
}

void MeasurementChain::validate() const {
  if (!(sample_rate_hz >= 0)) throw InputError("measurement chain: sample_rate_hz must be >= 0");
  if (!(converter_delay_s >= 0))
    throw InputError("measurement chain: converter_delay_s must be >= 0");
}

Json chain_to_json(const MeasurementChain& c) {
  return {{"sample_rate_hz", c.sample_rate_hz},
          {"hold", c.hold == MeasurementChain::Hold::kFirstOrder ? "first_order" : "zero_order"},
          {"converter_delay_s", c.converter_delay_s},
          {"reheld_inputs", c.reheld_inputs}};
}

MeasurementChain chain_from_json(const Json& j, const JsonWhere& where) {
  json_require_object(j, where);
  MeasurementChain c;
  c.sample_rate_hz = json_number_member(j, where, "sample_rate_hz");
  const std::string hold = json_string_member(j, where, "hold");
  if (hold == "first_order")
    c.hold = MeasurementChain::Hold::kFirstOrder;
  else if (hold == "zero_order")
    c.hold = MeasurementChain::Hold::kZeroOrder;
  else
    json_fail(where / "hold", "\"" + hold + "\": first_order or zero_order");
  c.converter_delay_s = json_number_member(j, where, "converter_delay_s", 0.0);
  const Json& re = json_array_member(j, where, "reheld_inputs", true);
  for (size_t i = 0; i < re.size(); ++i) {
    if (!re[i].is_string()) json_fail(where / "reheld_inputs" / i, "expected an input name");
    c.reheld_inputs.push_back(re[i]);
  }
  try {
    c.validate();
  } catch (const InputError& e) {
    json_fail(where, e.what());
  }
  return c;
}

std::string chain_to_message(const MeasurementChain& c) {
  return kChainMessagePrefix + chain_to_json(c).dump();
}

std::optional<MeasurementChain> chain_from_message(const std::string& message,
                                                   const std::string& where) {
  const std::string prefix = kChainMessagePrefix;
  if (message.rfind(prefix, 0) != 0) return std::nullopt;
  return chain_from_json(
      json_parse_text(message.substr(prefix.size()), where + ": measurement chain"), {where, ""});
}

}  // namespace fralab
