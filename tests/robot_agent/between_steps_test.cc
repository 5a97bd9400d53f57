#include "robot_agent/node/between_steps.h"

#include <chrono>

#include <gtest/gtest.h>

namespace mrslam::robot_agent {
namespace {

using std::chrono::milliseconds;
using Clock = BetweenSteps::Clock;

TEST(BetweenSteps, DueHalfwayToTheNextStepByTheLastInterval) {
  BetweenSteps schedule;
  const Clock::time_point t0{};
  EXPECT_FALSE(schedule.Due().has_value());
  schedule.Started(1, t0);
  EXPECT_FALSE(schedule.Due().has_value());  // one step: no interval yet
  schedule.Started(2, t0 + milliseconds(100));
  ASSERT_TRUE(schedule.Due().has_value());
  EXPECT_EQ(*schedule.Due(), t0 + milliseconds(150));
  schedule.Started(3, t0 + milliseconds(180));  // the interval follows the steps
  EXPECT_EQ(*schedule.Due(), t0 + milliseconds(220));
}

TEST(BetweenSteps, NothingDueAfterAGapInTheSteps) {
  BetweenSteps schedule;
  const Clock::time_point t0{};
  schedule.Started(7, t0);
  schedule.Started(9, t0 + milliseconds(100));  // a restored agent, or steps not in a row
  EXPECT_FALSE(schedule.Due().has_value());
  schedule.Started(10, t0 + milliseconds(140));
  EXPECT_EQ(*schedule.Due(), t0 + milliseconds(160));
}

}  // namespace
}  // namespace mrslam::robot_agent
