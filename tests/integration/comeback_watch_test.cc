// How the launcher tells that a restarted agent is back at the newest step.
#include "scripts/launch/comeback_watch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace mrslam::launch {
namespace {

using Clock = ComebackWatch::Clock;
using ::testing::ElementsAre;

Progress At(int clock_step, std::map<std::string, int> robot_steps) {
  Progress p;
  p.clock_step = clock_step;
  p.robot_steps = std::move(robot_steps);
  return p;
}

TEST(ComebackWatchTest, ARestartedRobotIsBackOnceItsEstimatesReachTheClock) {
  ComebackWatch watch;
  const Clock::time_point t0{};
  EXPECT_TRUE(watch.Update(At(40, {{"r1", 40}, {"r2", 39}}), t0).empty());  // nobody restarted
  watch.Restarted("r2", t0);
  EXPECT_TRUE(watch.Update(At(40, {{"r1", 40}, {"r2", 12}}), t0 + std::chrono::milliseconds(100)).empty());
  const auto back = watch.Update(At(41, {{"r1", 41}, {"r2", 41}}), t0 + std::chrono::milliseconds(1500));
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].robot_id, "r2");
  EXPECT_EQ(back[0].step, 41);
  EXPECT_DOUBLE_EQ(back[0].seconds, 1.5);
  EXPECT_TRUE(watch.Update(At(42, {{"r1", 42}, {"r2", 42}}), t0 + std::chrono::seconds(2)).empty());  // once
  EXPECT_THAT(watch.seconds().at("r2"), ElementsAre(1.5));
  EXPECT_EQ(watch.seconds().count("r1"), 0u);
}

TEST(ComebackWatchTest, ARobotKilledBeforeTheFirstStepIsBackAtStepOneNotBefore) {
  ComebackWatch watch;
  const Clock::time_point t0{};
  watch.Restarted("r1", t0);
  EXPECT_TRUE(watch.Update(At(0, {{"r1", 0}}), t0).empty());
  EXPECT_TRUE(watch.Update(At(0, {}), t0).empty());
  EXPECT_EQ(watch.Update(At(1, {{"r1", 1}}), t0 + std::chrono::seconds(1)).size(), 1u);
}

}  // namespace
}  // namespace mrslam::launch
