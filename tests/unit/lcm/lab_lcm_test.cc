// A lab process's LCM instances (fralab/lcm/lab_lcm.h): opened and checked, a receive port held
// by another socket an error naming the URL.
#include "fralab/lcm/lab_lcm.h"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>

#include "fralab/core/error.h"

using namespace fralab;

namespace {

// A UDP socket bound to an ephemeral port without SO_REUSEADDR, as LCM's own send sockets hold
// theirs (port 0: the bind failed). Closed at the end of the scope.
struct HeldPort {
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  int port = 0;
  HeldPort() {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_ANY);
    a.sin_port = 0;
    socklen_t len = sizeof a;
    if (fd >= 0 && bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
      port = ntohs(a.sin_port);
  }
  ~HeldPort() {
    if (fd >= 0) close(fd);
  }
  HeldPort(const HeldPort&) = delete;
  HeldPort& operator=(const HeldPort&) = delete;
};

}  // namespace

// A port held by a socket without SO_REUSEADDR (as LCM's own send sockets hold their ephemeral
// ports) cannot be bound by LCM's receiver: require_lcm says so, naming the URL, where LCM 1.3
// printed "bind: Address already in use" and crashed the process at a later call. A memq:// LCM
// passes (its "socket" is a pipe).
TEST(RequireLcm, AReceivePortHeldByAnotherSocketIsAnErrorNamingTheUrl) {
  const HeldPort held_port;
  ASSERT_GT(held_port.port, 0);
  const std::string url = "udpm://239.255.201.7:" + std::to_string(held_port.port) + "?ttl=0";
  lcm::LCM held(url);
  try {
    require_lcm(held, "the test's LCM", url);
    ADD_FAILURE() << "no error for a held port";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("cannot receive on the test's LCM at " + url));
  }
  lcm::LCM memq("memq://");
  EXPECT_NO_THROW(require_lcm(memq, "memq", "memq://"));
}

// A lab process's two instances: the control URL is the data URL's port + 1 unless given, and a
// held control port is an error naming the control URL (not the data URL).
TEST(LabLcm, TheControlUrlIsTheNextPortUnlessGivenAndAHeldOneIsNamed) {
  const HeldPort held_port;
  const int held = held_port.port;
  ASSERT_GT(held, 1);
  auto url = [](int port) { return "udpm://239.255.201.8:" + std::to_string(port) + "?ttl=0"; };
  {
    const LabLcm io(url(held + 2), "");
    EXPECT_EQ(io.data_url, url(held + 2));
    EXPECT_EQ(io.control_url, url(held + 3));
  }
  {
    const LabLcm io(url(held + 2), url(held + 6));
    EXPECT_EQ(io.control_url, url(held + 6));
  }
  try {
    const LabLcm io(url(held - 1), "");  // its control port is the held one
    ADD_FAILURE() << "no error for a held control port";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(),
                ::testing::HasSubstr("cannot receive on the control LCM URL at " + url(held)));
  }
}
