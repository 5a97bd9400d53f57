#include "world_sim/evaluator/truth_path.h"

#include <limits>

#include <gtest/gtest.h>

namespace mrslam::evaluator {
namespace {

TEST(TruthPathTest, FindsEachStepSetInAnyOrderAndNothingElse) {
  TruthPath path;
  path.SetLastStep(100);
  path.Set(7, {1.0, 2.0, 0.5});
  path.Set(3, {-1.0, 0.25, -0.5});
  path.Set(7, {1.5, 2.0, 0.5});  // sent again, corrected
  ASSERT_NE(path.Find(3), nullptr);
  EXPECT_DOUBLE_EQ(path.Find(3)->y, 0.25);
  ASSERT_NE(path.Find(7), nullptr);
  EXPECT_DOUBLE_EQ(path.Find(7)->x, 1.5);
  EXPECT_EQ(path.Find(5), nullptr);  // a gap
  EXPECT_EQ(path.Find(8), nullptr);  // past the newest
  EXPECT_EQ(path.Find(0), nullptr);
}

TEST(TruthPathTest, KeepsNoStepBeyondTheRunsLastNorANonFinitePose) {
  TruthPath path;
  path.SetLastStep(10);
  path.Set(10, {1.0, 1.0, 0.0});
  path.Set(4'000'000'000U, {1.0, 1.0, 0.0});  // a forged step: nothing allocated for it
  path.Set(2, {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0});
  EXPECT_NE(path.Find(10), nullptr);
  EXPECT_EQ(path.Find(4'000'000'000U), nullptr);
  EXPECT_EQ(path.Find(11), nullptr);
  EXPECT_EQ(path.Find(2), nullptr);
}

}  // namespace
}  // namespace mrslam::evaluator
