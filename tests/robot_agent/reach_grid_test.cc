// Where a robot's lidar has reached (ReachGrid): the cells marked from a pose, a limited field of
// view, and marks kept as the grid grows to places far from the first.
#include "robot_agent/cooperation/reach_grid.h"

#include <gtest/gtest.h>

#include <cmath>

namespace mrslam::robot_agent::cooperation {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(ReachGrid, MarksWhatLiesWithinRangeAndView) {
  ReachGrid g(0.5);
  EXPECT_FALSE(g.AnyWithin({0.0, 0.0}, 100.0));
  g.Mark({0.0, 0.0, 0.0}, 6.0, kPi / 4, 0.0);  // a 90-degree view along +x
  EXPECT_TRUE(g.AnyWithin({5.0, 0.0}, 0.5));
  EXPECT_TRUE(g.AnyWithin({3.0, 2.0}, 0.5));    // 34 degrees off the heading
  EXPECT_FALSE(g.AnyWithin({0.0, 4.0}, 0.5));   // beside the robot
  EXPECT_FALSE(g.AnyWithin({-4.0, 0.0}, 0.5));  // behind it
  EXPECT_FALSE(g.AnyWithin({8.0, 0.0}, 1.0));   // beyond its range
  EXPECT_TRUE(g.AnyWithin({8.0, 0.0}, 2.5));    // but within 2.5 m of what it reached
}

TEST(ReachGrid, AMarginWidensTheReach) {
  ReachGrid g(0.5);
  g.Mark({0.0, 0.0, 0.0}, 6.0, kPi, 1.0);
  EXPECT_TRUE(g.AnyWithin({6.7, 0.0}, 0.3));
  EXPECT_FALSE(g.AnyWithin({7.6, 0.0}, 0.3));
}

TEST(ReachGrid, KeepsItsMarksAsItGrowsAnywhere) {
  ReachGrid g(0.5);
  const common::Pose2 places[] = {{0.0, 0.0, 0.0}, {100.0, 3.0, 0.0}, {-50.0, -80.0, 1.0}, {20.0, 60.0, 2.0}};
  for (const auto& p : places) g.Mark(p, 3.0, kPi, 0.0);
  for (const auto& p : places) {
    EXPECT_TRUE(g.AnyWithin({p.x + 2.0, p.y}, 0.5)) << p.x << ", " << p.y;
    EXPECT_FALSE(g.AnyWithin({p.x + 4.0, p.y}, 0.5)) << p.x << ", " << p.y;
  }
  EXPECT_FALSE(g.AnyWithin({50.0, 30.0}, 5.0));
  common::Archive out = common::Archive::ForWriting();
  g.Io(out);
  ReachGrid back(0.5);
  common::Archive in = common::Archive::ForReading(out.bytes());
  back.Io(in);
  EXPECT_TRUE(in.AtEnd());
  for (const auto& p : places) EXPECT_TRUE(back.AnyWithin({p.x + 2.0, p.y}, 0.5));
  EXPECT_EQ(back.Bytes(), g.Bytes());
}

TEST(ReachGrid, NeverGrowsBeyondItsBoundNorMarksFromAPoseNotFinite) {
  ReachGrid g(0.5);
  g.Mark({0.0, 0.0, 0.0}, 6.0, kPi, 0.0);
  const std::size_t bytes = g.Bytes();
  g.Mark({1e5, 0.0, 0.0}, 6.0, kPi, 0.0);  // 200,000 cells away: beyond kMaxCellsPerAxis
  g.Mark({std::nan(""), 0.0, 0.0}, 6.0, kPi, 0.0);
  g.Mark({1e300, -1e300, 0.0}, 6.0, kPi, 0.0);
  EXPECT_EQ(g.Bytes(), bytes);
  EXPECT_FALSE(g.AnyWithin({1e5, 0.0}, 3.0));
  EXPECT_FALSE(g.AnyWithin({std::nan(""), 0.0}, 3.0));
  EXPECT_TRUE(g.AnyWithin({2.0, 0.0}, 0.5));
  g.Mark({900.0, 900.0, 0.0}, 6.0, kPi, 0.0);  // 1,800 cells away: within the bound
  EXPECT_TRUE(g.AnyWithin({902.0, 900.0}, 0.5));
  EXPECT_TRUE(g.AnyWithin({2.0, 0.0}, 0.5));
  EXPECT_LE(g.Bytes(), static_cast<std::size_t>(ReachGrid::kMaxCellsPerAxis) * ReachGrid::kMaxCellsPerAxis);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
