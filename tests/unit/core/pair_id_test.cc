// The pair's name parsed once (pair_id.h): each of the lab's three kinds of pair, back to its text,
// and names that are not pairs refused naming the text.
#include "fralab/core/pair_id.h"

#include <gtest/gtest.h>

#include "fralab/core/error.h"

namespace fralab {
namespace {

TEST(PairId, TheLabsThreeKindsOfPairAreToldApartAndWrittenBack) {
  const PairId path = PairId::parse("Wf:P3");
  EXPECT_EQ(path.input, "Wf");
  EXPECT_EQ(path.output, "P3");
  EXPECT_TRUE(path.path());
  EXPECT_FALSE(path.actuator());
  const PairId actuator = PairId::parse("u_A8:A8");
  EXPECT_EQ(actuator.input, "A8");
  EXPECT_TRUE(actuator.actuator());
  EXPECT_FALSE(actuator.path());
  const PairId command = PairId::parse("u_A8:N");
  EXPECT_EQ(command.input, "A8");
  EXPECT_EQ(command.output, "N");
  EXPECT_FALSE(command.actuator());
  EXPECT_FALSE(command.path());
  for (const char* t : {"Wf:P3", "u_A8:A8", "u_A8:N"}) EXPECT_EQ(PairId::parse(t).str(), t);
}

// The tape names an input X's command u_X and its position X; a pair's E1 is one of the two.
TEST(PairId, AnInputsCommandChannelAndTheFirstChannelOfItsPairs) {
  EXPECT_EQ(command_channel("A8"), "u_A8");
  EXPECT_EQ(commanded_input("u_A8"), "A8");
  EXPECT_EQ(commanded_input(command_channel("Wf")), "Wf");
  for (const char* ch : {"A8", "ref_phase", "underrun", "N_u_"})
    EXPECT_FALSE(commanded_input(ch).has_value()) << ch;
  EXPECT_EQ(PairId::actuator_pair("A8").str(), "u_A8:A8");
  EXPECT_TRUE(PairId::actuator_pair("A8").actuator());
  EXPECT_EQ(PairId::parse("u_A8:N").e1(), "u_A8");
  EXPECT_EQ(PairId::parse("A8:N").e1(), "A8");
}

TEST(PairId, TextThatIsNoPairIsRefusedNamingIt) {
  for (const char* t : {"WfP3", "u_:A8", ":P3", "Wf:"}) {
    try {
      PairId::parse(t);
      ADD_FAILURE() << t << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(t), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace fralab
