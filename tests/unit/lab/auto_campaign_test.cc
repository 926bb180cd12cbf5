// The auto campaign's decision (lab/auto_campaign.h): which actuators distort at the multisine's
// level, from their actuator curve's nl_rel.
#include "fralab/lab/auto_campaign.h"

#include <gtest/gtest.h>

namespace fralab {
namespace {

FrdPoint point(double w, double rel_sigma, double nl, bool valid = true) {
  FrdPoint p;
  p.w = w;
  p.mag = 2.0;
  p.sigma = rel_sigma * 2.0;
  p.nl_rel = nl;
  p.valid = valid;
  return p;
}

// The median nl_rel over the valid points measured to better than max_rel_sigma: here the points
// with nl 0.2, 0.4, 0.6, 0.8 qualify (median 0.5); a noisy point (nl 5) and an invalid one (nl 9)
// do not count.
TEST(AutoCampaign, DistortionIsTheMedianOverWellMeasuredLines) {
  Frd f;
  f.pair = "u_A8:A8";
  f.points = {point(1, 1e-3, 0.6), point(2, 1e-3, 0.2),        point(3, 0.05, 5.0),
              point(4, 1e-3, 0.8), point(5, 1e-3, 9.0, false), point(6, 5e-3, 0.4)};
  EXPECT_DOUBLE_EQ(actuator_distortion(f, 0.01), 0.5);
  EXPECT_DOUBLE_EQ(actuator_distortion(f, 0.1), 0.6);  // the noisy point too: 0.2 0.4 0.6 0.8 5
  f.points = {point(1, 0.5, 0.1)};
  EXPECT_EQ(actuator_distortion(f, 0.01), -1);  // nothing measured well enough: unknown
}

TEST(AutoCampaign, OptionsAreValidatedByName) {
  AutoCampaignOptions a;
  EXPECT_NO_THROW(a.validate());
  a.nl_threshold = 0;
  EXPECT_THROW(a.validate(), InputError);
  a = {};
  a.sine_min_cycles = 1;
  try {
    a.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sine_min_cycles"), std::string::npos);
  }
  MeasureOptions m;
  m.out = "/tmp/x";
  m.resume = true;
  EXPECT_THROW(run_auto_campaign(m), InputError);
}

}  // namespace
}  // namespace fralab
