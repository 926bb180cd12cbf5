// The lab's measurement chain (core/measurement_chain.h): its factors, and its record on the tape
// (the start event's message) read back exactly or refused naming where.
#include "fralab/core/measurement_chain.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fralab/core/error.h"

using namespace fralab;
using ::testing::HasSubstr;

TEST(MeasurementChain, FirstOrderHoldIsSincSquaredWithoutPhaseAndZeroOrderHalfASampleLate) {
  MeasurementChain c;
  c.sample_rate_hz = 1000;
  const double w = 2 * M_PI * 100, x = w / 2000;
  EXPECT_NEAR(std::abs(c.command_factor(w) - std::pow(std::sin(x) / x, 2)), 0, 1e-15);
  c.hold = MeasurementChain::Hold::kZeroOrder;
  EXPECT_NEAR(std::arg(c.command_factor(w)), -x, 1e-15);
  c.reheld_inputs = {"A8"};
  EXPECT_EQ(c.pair_factor("Wf", w), std::complex<double>(1.0));  // two recorded channels
  EXPECT_EQ(c.pair_factor("A8", w), c.command_factor(w));        // the reheld input's paths
  EXPECT_EQ(c.pair_factor("u_Wf", w), c.command_factor(w));      // referred to the command
}

TEST(MeasurementChain, TheTapesRecordReadsBackAndOtherMessagesAreNotChains) {
  MeasurementChain c;
  c.sample_rate_hz = 1000;
  c.converter_delay_s = 2.5e-4;
  c.reheld_inputs = {"A8", "BLD"};
  const std::string m = chain_to_message(c);
  EXPECT_THAT(m, ::testing::StartsWith("measurement_chain: {"));
  const auto back = chain_from_message(m, "tape: event 0");
  ASSERT_TRUE(back);
  EXPECT_EQ(chain_to_json(*back), chain_to_json(c));
  EXPECT_FALSE(chain_from_message("stopped by a signal", "x"));
  EXPECT_FALSE(chain_from_message("", "x"));
  EXPECT_THAT(
      [] { chain_from_message("measurement_chain: {\"sample_rate_hz\": ", "tape: event 3"); },
      ::testing::ThrowsMessage<InputError>(HasSubstr("tape: event 3: measurement chain")));
  EXPECT_THAT(
      [] { chain_from_message("measurement_chain: {\"sample_rate_hz\": -5}", "tape: event 3"); },
      ::testing::ThrowsMessage<InputError>(HasSubstr("tape: event 3")));
  const std::string deep =
      "measurement_chain: " + std::string(100000, '[') + std::string(100000, ']');
  EXPECT_THAT([&] { chain_from_message(deep, "tape: event 4"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("nested deeper than")));
}
