// The URL policy (fralab/lcm/url.h): the ttl option parsed, leaving the host an opt-in, private
// URLs on even ports outside the ephemeral range; and the run id peeked from a message's bytes.
#include "fralab/lcm/url.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>

#include "fralab/ack_t.hpp"
#include "fralab/lcm/codec.h"

using namespace fralab;

// The URL policy: the ttl option parsed (not a substring), ttl >= 1 only on the explicit opt-in.
TEST(LcmUrl, TtlIsParsedAndLeavingTheHostIsAnOptIn) {
  unsetenv("FRALAB_NETWORK");
  EXPECT_EQ(resolve_lcm_url("udpm://239.255.1.2:7667?ttl=0"), "udpm://239.255.1.2:7667?ttl=0");
  EXPECT_NO_THROW(resolve_lcm_url("udpm://239.255.1.2:7667?recv_buf_size=2097152&ttl=0"));
  EXPECT_NO_THROW(resolve_lcm_url("memq://"));
  for (const char* bad : {"udpm://239.255.1.2:7667?ttl=05", "udpm://239.255.1.2:7667?ttl=0x1",
                          "udpm://239.255.1.2:7667?ttl=", "udpm://239.255.1.2:7667?ttl=256"}) {
    try {
      resolve_lcm_url(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("is not a number 0-255")) << bad;
    }
  }
  EXPECT_THROW(resolve_lcm_url("udpm://239.255.1.2:7667"), InputError);         // ttl unstated
  EXPECT_THROW(resolve_lcm_url("udpm://239.255.1.2:7667?xttl=0"), InputError);  // not ttl
  try {
    resolve_lcm_url("udpm://239.255.1.2:7667?ttl=1");
    ADD_FAILURE() << "ttl=1 without the opt-in";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("set FRALAB_NETWORK=1"));
  }
  setenv("FRALAB_NETWORK", "1", 1);
  EXPECT_NO_THROW(resolve_lcm_url("udpm://239.255.1.2:7667?ttl=1"));
  unsetenv("FRALAB_NETWORK");
}

// Every port even, P and P + 1 outside the ephemeral range (Linux's default, a custom one, and
// the range this kernel reports), each used once over as many salts as there are ports.
TEST(LcmUrl, PrivateUrlsUseAnEvenPortOutsideTheEphemeralRangeAndThePeekFindsTheRunId) {
  auto port_of = [](const std::string& u) {
    const auto colon = u.rfind(':'), q = u.find('?');
    return std::stoi(u.substr(colon + 1, q - colon - 1));
  };
  const std::pair<int, int> ranges[] = {{32768, 60999}, {20001, 40000}, ephemeral_port_range()};
  for (const auto& [lo, hi] : ranges) {
    int expected = 0;  // counted directly, not by the implementation's segment arithmetic
    for (int p = 10000; p <= 65534; p += 2) expected += (p + 1 < lo || p > hi) ? 1 : 0;
    if (expected == 0) continue;  // a kernel range covering every port: nothing to keep clear of
    std::set<int> ports;
    for (uint64_t s = 0; s < uint64_t(expected); ++s) {
      const std::string u = private_lcm_url(s * 62500, {lo, hi});
      const int port = port_of(u);
      EXPECT_EQ(port % 2, 0) << u;
      EXPECT_GE(port, 10000) << u;
      EXPECT_LE(port, 65534) << u;
      EXPECT_TRUE(port + 1 < lo || port > hi) << u << " in the ephemeral range " << lo << "-" << hi;
      ports.insert(port);
      EXPECT_NO_THROW(resolve_lcm_url(u));
    }
    EXPECT_EQ(int(ports.size()), expected) << lo << "-" << hi;  // every port used once
  }
  EXPECT_EQ(port_of(private_lcm_url(0, {32768, 60999})), 10000);
  EXPECT_EQ(port_of(private_lcm_url(11384 * 62500, {32768, 60999})), 61000);
  ack_t a;
  a.run_id = "run-42";
  a.consumer = "c";
  a.seq = 1;
  a.stream = "tape";
  std::vector<uint8_t> buf(size_t(a.getEncodedSize()));
  a.encode(buf.data(), 0, int(buf.size()));
  EXPECT_EQ(peek_run_id(buf.data(), buf.size()), "run-42");
  EXPECT_EQ(peek_run_id(buf.data(), 10), std::nullopt);
  buf[8] = 0x7f;  // absurd length
  EXPECT_EQ(peek_run_id(buf.data(), buf.size()), std::nullopt);
}
