// The acquisition's protocol logic (acquire/acquisition.h) and the plant's lockstep
// (plant/lockstep.h), without LCM: command blocks cover the campaign sample-exactly, bad options
// are named, and the plant refuses a gap naming the sequence numbers (the flags that reproduce the
// options: acquire_flags_test).
#include "fralab/acquire/acquisition.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fralab/plant/embedded_models.h"
#include "fralab/plant/lockstep.h"

namespace fralab {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

AcquireOptions short_run() {
  AcquireOptions o;
  o.inputs = "Wf";
  o.band = "1:10";
  o.points_per_decade = 2;
  o.min_integrate_s = 1.0;
  return o;
}

TEST(Acquisition, CommandBlocksCoverTheCampaignExactly) {
  const Model m = load_model_or_embedded("j85_95");
  const auto camp = make_campaign(m, short_run(), "r");
  const int block = 100;
  const int64_t n = command_block_count(*camp, block);
  ASSERT_GT(n, 1);
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr;
  int64_t samples = 0;
  for (int64_t s = 0; s < n; ++s) {
    const Block b = command_block(*camp, s, block, 1000.0, "r");
    EXPECT_EQ(b.seq, s);
    EXPECT_EQ(b.start_sample, samples);
    EXPECT_EQ(b.final_block, s == n - 1);
    EXPECT_EQ(b.channels.back(), "ref_freq_hz");
    EXPECT_EQ(b.samples.size(), b.channels.size() * size_t(b.n_samples));
    // The block holds the campaign's own samples.
    camp->fill(b.start_sample, b.n_samples, cmd, ph, fr);
    EXPECT_DOUBLE_EQ(b.at(b.channel_index("u_Wf"), b.n_samples - 1), cmd[0][b.n_samples - 1]);
    EXPECT_DOUBLE_EQ(b.at(b.channel_index("ref_phase"), 0), ph[0]);
    samples += b.n_samples;
  }
  EXPECT_EQ(samples, camp->total_samples());
}

TEST(Acquisition, BadOptionsAreNamed) {
  AcquireOptions o = short_run();
  o.window = 0;
  EXPECT_THROW(o.validate(), InputError);
  o = short_run();
  o.multisine_phases = "chirp";
  try {
    o.validate();
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--multisine-phases \"chirp\""));
  }
  EXPECT_THROW(excitation_from_string("steppedsine"), InputError);
  EXPECT_EQ(excitation_from_string(to_string(Excitation::kSweep)), Excitation::kSweep);
}

TEST(Acquisition, BlocksAreSizedToTheSampleRateUnderADatagram) {
  Model m = load_model_or_embedded("j85_95");  // 4 inputs, 5 outputs: 2 x 4 + 5 + 2 = 15 channels
  AcquireOptions o = short_run();
  ASSERT_EQ(o.block, 0);
  EXPECT_EQ(block_samples(m, o), 500);  // half a second at 1 kHz; 500 x 15 x 8 B = 60 kB
  o.sample_rate_hz = 400;
  EXPECT_EQ(block_samples(m, o), 200);  // half a second
  o.sample_rate_hz = 1000;
  while (m.outputs.size() < 16) {
    auto extra = m.outputs.back();
    extra.name += "x";
    m.outputs.push_back(extra);
  }
  EXPECT_EQ(block_samples(m, o), 288);  // 26 channels: floor(60000 / (8 x 26))
  o.block = 100;
  EXPECT_EQ(block_samples(m, o), 100);  // given, kept
  o.block = 289;
  try {
    block_samples(m, o);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--block 289"));
    EXPECT_THAT(e.what(), HasSubstr("at most 288"));
  }
  o.block = -1;
  EXPECT_THROW(o.validate(), InputError);
}

TEST(Lockstep, ThePlantEchoesCommandsAndRefusesAGap) {
  const Model m = load_model_or_embedded("j85_95");
  const auto camp = make_campaign(m, short_run(), "r");
  SimulatorOptions so;
  so.noise = false;
  LockstepPlant plant(m, so);
  EXPECT_TRUE(plant.accepts("r"));
  EXPECT_FALSE(plant.accepts("other-run"));
  const Block c0 = command_block(*camp, 0, 100, 1000.0, "r");
  const Block t0 = plant.advance(c0);
  EXPECT_EQ(t0.seq, 0);
  EXPECT_THAT(std::vector<std::string>(t0.channels.begin(), t0.channels.begin() + 4),
              ElementsAre("u_Wf", "u_A8", "u_BLD", "u_IGV"));
  EXPECT_EQ(t0.channels.back(), "ref_freq_hz");
  EXPECT_DOUBLE_EQ(t0.at(0, 50), c0.at(c0.channel_index("u_Wf"), 50));
  const Block c2 = command_block(*camp, 2, 100, 1000.0, "r");
  try {
    plant.advance(c2);
    ADD_FAILURE() << "a gap was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("expected seq 1, got 2"));
  }
  Block c1 = command_block(*camp, 1, 100, 1000.0, "r");
  c1.channels[0] = "u_XX";
  EXPECT_THROW(plant.advance(c1), InputError);
}

}  // namespace
}  // namespace fralab
