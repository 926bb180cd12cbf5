// Multi-host, on purpose: two network namespaces joined by a veth pair
// (scripts/two_hosts.sh), the plant, recorder and every analyser on "host" A through its deputy
// (fralab-deputy), the launcher, acquisition and identifier on B. The numbers must be identical
// to a run on one host; a deputy that is not there is named.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "shell.h"

using fralab::testing::sh;
using fralab::testing::slurp;
using fralab::testing::tmpdir;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

const std::string kBin = FRALAB_BIN_DIR;
const std::string kScripts = FRALAB_SCRIPTS_DIR;
const std::string kRun =
    " measure --engine j85_95 --input Wf --band 0.5:20 --points-per-decade 3 --seed 4 ";

TEST(MultiHost, ModulesOnAnotherHostThroughItsDeputyGiveTheOneHostNumbers) {
  const std::string one = tmpdir("one_host"), two = tmpdir("two_hosts");
  auto c = sh(kScripts + "/isolated.sh " + kBin + "/fralab" + kRun + "--out " + one);
  ASSERT_EQ(c.status, 0) << c.output;
  c = sh(kScripts + "/two_hosts.sh " + kBin + " " + kBin + "/fralab" + kRun +
         "--on plant=A,recorder=A,analyze=A --out " + two);
  ASSERT_EQ(c.status, 0) << c.output;
  int files = 0;
  for (const char* sub : {"frd", "tf"}) {
    for (const auto& f : fs::directory_iterator(one + "/" + sub)) {
      const std::string name = std::string(sub) + "/" + f.path().filename().string();
      EXPECT_EQ(slurp(f.path().string()), slurp(two + "/" + name)) << name;
      ++files;
    }
  }
  EXPECT_EQ(files, 22);
  EXPECT_EQ(slurp(one + "/transfer_matrix.json"), slurp(two + "/transfer_matrix.json"));
  // The run crossed the veth: its URL left the host (ttl=1) and the deputy ran the plant.
  EXPECT_THAT(slurp(two + "/run.json"), HasSubstr("ttl=1"));
  EXPECT_THAT(slurp(two + "/logs/plant.log"), ::testing::Not(HasSubstr("error")));
}

TEST(MultiHost, ADeputyThatIsNotThereIsNamedAndLeavingTheHostIsAnOptIn) {
  const std::string d = tmpdir("no_deputy");
  auto c = sh(kScripts + "/two_hosts.sh " + kBin + " " + kBin + "/fralab" + kRun +
              "--on plant=Z --out " + d);
  EXPECT_NE(c.status, 0);
  EXPECT_THAT(c.output, HasSubstr("deputy \"Z\" not heard"));
  c = sh("env -u FRALAB_NETWORK " + kScripts + "/isolated.sh " + kBin + "/fralab" + kRun +
         "--on plant=A --out " + d);
  EXPECT_NE(c.status, 0);
  EXPECT_THAT(c.output, HasSubstr("set FRALAB_NETWORK=1"));
}

}  // namespace
