// Deputies (lab/deputy.h) over memq:// in one process: the launcher's Supervisor starts processes
// on "host" A through DeputyClient and DeputyNode, sees their exits and reasons as for local ones,
// stops them, and names a deputy that is silent.
#include "fralab/lab/deputy.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>

namespace fralab {
namespace {

using ::testing::HasSubstr;

std::string log_file(const std::string& n) {
  return (std::filesystem::temp_directory_path() / ("deputy_test_" + n + ".log")).string();
}

// Drives both sides until `name` has exited (or 10 s).
std::optional<RemoteProcesses::Exit> run_until_exit(DeputyNode& node, Supervisor& sup,
                                                    const std::string& name) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10)) {
    node.tick(10);
    sup.poll();
    if (auto e = sup.exit_of(name)) return e;
  }
  return std::nullopt;
}

TEST(Deputy, StartsReportsAndStopsProcessesOnItsHost) {
  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  DeputyNode node(bus, "A");
  DeputyClient client(bus, "run-1");
  Supervisor sup;
  sup.set_remote(&client);
  client.poll(0);
  node.tick(0);
  client.wait_for_deputy("A", 2);

  sup.start({"fine", {"true"}, log_file("fine"), "A"});
  auto e = run_until_exit(node, sup, "fine");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->status, 0);

  sup.start({"broken", {"sh", "-c", "echo the reason >&2; exit 3"}, log_file("broken"), "A"});
  e = run_until_exit(node, sup, "broken");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->status, 3);
  EXPECT_THAT(e->reason, HasSubstr("broken exited with status 3: the reason"));

  sup.start({"missing", {"/no/such/fralab-thing"}, log_file("missing"), "A"});
  e = run_until_exit(node, sup, "missing");
  ASSERT_TRUE(e);
  EXPECT_NE(e->status, 0);

  sup.start({"sleeper", {"sleep", "30"}, log_file("sleeper"), "A"});
  for (int i = 0; i < 20; ++i) node.tick(10), client.poll(0);
  EXPECT_FALSE(sup.exit_of("sleeper"));
  client.stop("sleeper");
  e = run_until_exit(node, sup, "sleeper");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->status, -1);  // killed by SIGTERM
}

TEST(Deputy, ASilentDeputyIsNamed) {
  lcm::LCM bus("memq://");
  DeputyClient client(bus, "run-2", 0.2);
  Supervisor sup;
  sup.set_remote(&client);
  EXPECT_THROW(client.wait_for_deputy("B", 0.2), InputError);
  sup.start({"p", {"true"}, log_file("p"), "B"});
  try {
    sup.wait_for({"p"}, 5);
    ADD_FAILURE() << "no deputy B, yet the wait ended";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("deputy \"B\" is silent (never heard)"));
  }
  Supervisor local;
  EXPECT_THROW(local.start({"q", {"true"}, "", "C"}), InputError);  // a host without deputies
}

}  // namespace
}  // namespace fralab
