// The transfer matrix and the state model on every shape of data the lab can hand them
// (tests/util/random_shapes.h): random sets of 1-8 inputs x 1-8 outputs with missing paths, paths
// with no response, failed fits and fits at the maximum order, single points, repeated
// frequencies, per-path grids, with and without sigma. Each draw ends in a model or in a clear
// refusal (an InputError with its message); nothing crashes or hangs, and what is built is
// finite. The "shapes" fuzz target (tests/fuzz) runs the same under ASan and UBSan.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "fralab/identify/state_model.h"
#include "fralab/identify/transfer_matrix.h"
#include "random_shapes.h"

using namespace fralab;
using fralab::testing::random_shape_set;

namespace {

// The draws: seeds first() .. first() + draws() - 1 (FRALAB_SHAPES_FIRST and FRALAB_SHAPES_DRAWS
// set others, e.g. to replay one seed a failure names).
int env_int(const char* name, int fallback) {
  const char* e = std::getenv(name);
  return e ? std::atoi(e) : fallback;
}
int first() { return env_int("FRALAB_SHAPES_FIRST", 1); }
int draws() { return env_int("FRALAB_SHAPES_DRAWS", 300); }

bool finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

}  // namespace

TEST(IdentifyShapes, EveryRandomShapeEndsInAFiniteModelOrAClearRefusal) {
  int built = 0, refused = 0, single_input = 0;
  for (int seed = first(); seed < first() + draws(); ++seed) {
    const auto set = random_shape_set(uint64_t(seed));
    SCOPED_TRACE("seed " + std::to_string(seed) + ": " + set.description);
    single_input += set.inputs.size() == 1;
    try {
      const TransferMatrix m = build_transfer_matrix(set.entries);
      const StateModel s = build_state_model(m, set.data);
      ASSERT_EQ(s.A.rows(), s.order);
      ASSERT_EQ(s.B.rows(), s.order);
      ASSERT_EQ(s.C.cols(), s.order);
      EXPECT_TRUE(finite(s.A) && finite(s.B) && finite(s.C) && finite(s.D) && finite(s.delay_s));
      for (const auto& [pair, c] : s.path_check) {
        EXPECT_FALSE(std::isnan(c.error)) << pair;
        EXPECT_FALSE(std::isnan(c.chi2_per_point)) << pair;
      }
      EXPECT_FALSE(transfer_matrix_json(m).dump().empty());
      EXPECT_FALSE(state_model_json(s).dump().empty());
      EXPECT_FALSE(state_model_markdown(s).empty());
      ++built;
    } catch (const InputError& e) {
      EXPECT_GT(std::string(e.what()).size(), 10u) << "a refusal without its reason";
      ++refused;
    }
  }
  std::printf("%d draws (%d with one input): %d models, %d refused\n", draws(), single_input, built,
              refused);
  EXPECT_GT(built, draws() * 9 / 10);  // refusals are for data no model can be made of
  EXPECT_GT(single_input, draws() / 5);
}
