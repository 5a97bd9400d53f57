#pragma once

#include <cmath>

#include <gmock/gmock.h>

#include "common/angles.h"
#include "common/se2.h"

// Domain matchers shared by the tests (Cartographer's rigid_transform_test_helpers.h style).
namespace mrslam::testing {

// Matches a pose (common::Pose2) whose position lies within tol_m (Euclidean distance) of
// expected's and whose heading lies within tol_rad of expected's (the difference wrapped).
MATCHER_P3(IsNearlyPose, expected, tol_m, tol_rad, "") {
  const double dx = arg.x - expected.x;
  const double dy = arg.y - expected.y;
  const double dh = common::WrapAngle(arg.heading - expected.heading);
  *result_listener << "pose (" << arg.x << ", " << arg.y << ", " << arg.heading << ") against (" << expected.x << ", "
                   << expected.y << ", " << expected.heading << "): position off by " << std::hypot(dx, dy)
                   << " m, heading by " << dh << " rad";
  return std::hypot(dx, dy) <= tol_m && std::abs(dh) <= tol_rad;
}

}  // namespace mrslam::testing
