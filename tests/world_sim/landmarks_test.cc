#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "common/angles.h"
#include "common/se2.h"
#include "tests/world_sim/world_test_util.h"
#include "world_sim/core/landmark_motion.h"
#include "world_sim/core/world.h"

namespace mrslam::world_sim {
namespace {

using common::kPi;
using common::LandmarkMotionModel;
using testing::QuietScenario;
using testing::StaticLandmark;

constexpr double kExact = 1e-9;

common::ScenarioOptions FieldScenario(int count, double moving_fraction) {
  auto o = QuietScenario();
  o.seed = 11;
  o.landmarks = {StaticLandmark(100, 0.0, 0.0), StaticLandmark(101, 1.0, 0.0)};
  auto& f = o.landmark_field;
  f.enabled = true;
  f.count = count;
  f.area_m = {-18.0, -10.0, 18.0, 10.0};
  f.jitter_m = 0.6;
  f.moving_fraction = moving_fraction;
  f.speed_mps = 0.5;
  f.reverse_every_steps = 20;
  f.first_id = 1;
  return o;
}

TEST(ExpandLandmarksTest, ExplicitLandmarksThenTheField) {
  for (const int count : {1, 7, 48, 72, 101}) {
    for (const double fraction : {0.0, 0.2, 0.35, 1.0}) {
      SCOPED_TRACE(::testing::Message() << count << " landmarks, fraction " << fraction);
      const auto o = FieldScenario(count, fraction);
      const auto all = ExpandLandmarks(o);
      ASSERT_EQ(all.size(), 2u + count);
      EXPECT_EQ(all[0].id, 100);
      EXPECT_EQ(all[1].id, 101);
      int moving = 0;
      const auto& f = o.landmark_field;
      for (int i = 0; i < count; ++i) {
        const auto& l = all[2 + i];
        EXPECT_EQ(l.id, f.first_id + i);
        EXPECT_GE(l.pose.x, f.area_m[0] - f.jitter_m);
        EXPECT_LE(l.pose.x, f.area_m[2] + f.jitter_m);
        EXPECT_GE(l.pose.y, f.area_m[1] - f.jitter_m);
        EXPECT_LE(l.pose.y, f.area_m[3] + f.jitter_m);
        if (l.motion.model == LandmarkMotionModel::kCardinal) {
          ++moving;
          EXPECT_EQ(l.motion.speed_mps, f.speed_mps);
          EXPECT_EQ(l.motion.reverse_every_steps, f.reverse_every_steps);
          // One of the four cardinal directions.
          const double quarter = l.pose.heading / (kPi / 2.0);
          EXPECT_NEAR(quarter, std::round(quarter), kExact);
        } else {
          EXPECT_EQ(l.motion.model, LandmarkMotionModel::kStatic);
        }
      }
      EXPECT_EQ(moving, static_cast<int>(std::lround(fraction * count)));
    }
  }
}

TEST(ExpandLandmarksTest, FieldIsASpreadGrid) {
  auto o = FieldScenario(72, 0.0);
  o.landmarks.clear();
  o.landmark_field.jitter_m = 0.0;
  o.landmark_field.area_m = {-10.0, -10.0, 10.0, 10.0};
  const auto all = ExpandLandmarks(o);
  // Cells of a near-square grid are about sqrt(area / n) wide; without jitter no two
  // landmarks are closer than half of that.
  const double spacing = std::sqrt(400.0 / 72.0);
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      EXPECT_GT((all[i].pose.Translation() - all[j].pose.Translation()).norm(), 0.5 * spacing);
    }
  }
  // Every quadrant holds a quarter of them (to one row or column).
  int quadrant[4] = {0, 0, 0, 0};
  for (const auto& l : all) ++quadrant[(l.pose.x > 0 ? 1 : 0) + (l.pose.y > 0 ? 2 : 0)];
  for (const int q : quadrant) EXPECT_NEAR(q, 18, 5);
}

TEST(ExpandLandmarksTest, DeterministicForASeed) {
  const auto o = FieldScenario(48, 0.35);
  const auto a = ExpandLandmarks(o), b = ExpandLandmarks(o);
  auto other = o;
  other.seed = o.seed + 1;
  const auto c = ExpandLandmarks(other);
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].pose.x, b[i].pose.x);
    EXPECT_EQ(a[i].pose.y, b[i].pose.y);
    EXPECT_EQ(a[i].pose.heading, b[i].pose.heading);
    EXPECT_EQ(a[i].motion.model, b[i].motion.model);
    differs = differs || a[i].pose.x != c[i].pose.x || a[i].motion.model != c[i].motion.model;
  }
  EXPECT_TRUE(differs);
}

TEST(LandmarkMotionTest, CardinalLandmarkGoesAndComesBack) {
  common::LandmarkOptions l = StaticLandmark(3, 1.0, 2.0);
  l.pose.heading = kPi / 2.0;
  l.motion.model = LandmarkMotionModel::kCardinal;
  l.motion.speed_mps = 0.5;
  l.motion.reverse_every_steps = 20;
  SimLandmark landmark(l, 1);
  const Eigen::Vector3d no_noise = Eigen::Vector3d::Zero();
  for (int k = 1; k <= 40; ++k) {
    landmark.Step(1.0, no_noise);
    // Out for 20 steps at 0.5 m/s, then back.
    const double y = k <= 20 ? 2.0 + 0.5 * k : 2.0 + 0.5 * (40 - k);
    EXPECT_NEAR(landmark.pose().y, y, kExact) << "step " << k;
    EXPECT_NEAR(landmark.pose().x, 1.0, kExact);
  }
  EXPECT_NEAR(landmark.pose().heading, kPi / 2.0, kExact);
  EXPECT_TRUE(landmark.moving());
}

TEST(LandmarkMotionTest, UnicycleConstantVelocityAndStaticModels) {
  const Eigen::Vector3d no_noise = Eigen::Vector3d::Zero();
  common::LandmarkOptions u = StaticLandmark(1, -1.5, -1.0);
  u.pose.heading = 1.22;
  u.motion.model = LandmarkMotionModel::kUnicycle;
  u.motion.v_mps = 0.4;
  u.motion.w_radps = 0.2;
  common::LandmarkOptions cv = StaticLandmark(2, 0.0, 0.0);
  cv.motion.model = LandmarkMotionModel::kConstantVelocity;
  cv.motion.velocity_mps = {0.3, -0.1};
  SimLandmark unicycle(u, 1), constant(cv, 1), fixed(StaticLandmark(3, 4.0, 5.0), 1);
  common::Pose2 expected = u.pose;
  for (int k = 1; k <= 50; ++k) {
    unicycle.Step(0.65, no_noise);
    constant.Step(0.65, no_noise);
    // The static landmark ignores process noise.
    fixed.Step(0.65, Eigen::Vector3d::Constant(1.0));
    expected = common::UnicycleStep(expected, 0.4, 0.2, 0.65);
    EXPECT_NEAR(unicycle.pose().x, expected.x, kExact);
    EXPECT_NEAR(unicycle.pose().y, expected.y, kExact);
    EXPECT_NEAR(unicycle.pose().heading, expected.heading, kExact);
    EXPECT_NEAR(constant.pose().x, 0.3 * 0.65 * k, kExact);
    EXPECT_NEAR(constant.pose().y, -0.1 * 0.65 * k, kExact);
  }
  EXPECT_EQ(fixed.pose().x, 4.0);
  EXPECT_EQ(fixed.pose().y, 5.0);
  EXPECT_FALSE(fixed.moving());
  EXPECT_TRUE(unicycle.moving());
  EXPECT_TRUE(constant.moving());
}

TEST(LandmarkMotionTest, ProcessNoiseMatchesConfiguredCovariance) {
  const Eigen::Vector3d q(0.004, 0.001, 0.002);
  common::LandmarkOptions u = StaticLandmark(1, 0.0, 0.0);
  u.motion.model = LandmarkMotionModel::kUnicycle;
  u.motion.v_mps = 0.6;
  u.motion.w_radps = 0.2;
  common::LandmarkOptions c = StaticLandmark(2, 0.0, 0.0);
  c.motion.model = LandmarkMotionModel::kCardinal;
  c.motion.speed_mps = 0.5;
  c.motion.reverse_every_steps = 7;
  SimLandmark unicycle(u, 5), cardinal(c, 5);
  std::vector<double> ux, uy, uh, cx, cy;
  for (int k = 0; k < 2000; ++k) {
    const common::Pose2 before = unicycle.pose();
    unicycle.Step(1.0, q);
    const common::Pose2 predicted = common::UnicycleStep(before, 0.6, 0.2, 1.0);
    ux.push_back(unicycle.pose().x - predicted.x);
    uy.push_back(unicycle.pose().y - predicted.y);
    uh.push_back(common::WrapAngle(unicycle.pose().heading - predicted.heading));

    const common::Pose2 was = cardinal.pose();
    cardinal.Step(1.0, q);
    cx.push_back(cardinal.pose().x - (was.x + 0.5 * std::cos(was.heading)));
    cy.push_back(cardinal.pose().y - (was.y + 0.5 * std::sin(was.heading)));
    // Heading noise-free: one of the cardinal directions.
    const double quarter = cardinal.pose().heading / (kPi / 2.0);
    ASSERT_NEAR(quarter, std::round(quarter), kExact);
  }
  EXPECT_TRUE(testing::VarianceMatches(ux, q.x()));
  EXPECT_TRUE(testing::VarianceMatches(uy, q.y()));
  EXPECT_TRUE(testing::VarianceMatches(uh, q.z()));
  EXPECT_TRUE(testing::VarianceMatches(cx, q.x()));
  EXPECT_TRUE(testing::VarianceMatches(cy, q.y()));
}

TEST(LandmarkMotionTest, WorldLandmarksUseTheirOwnStreams) {
  // Adding a landmark must not change another landmark's noise samples.
  auto o = QuietScenario();
  o.noise.landmark_process_var = Eigen::Vector3d::Constant(0.01);
  common::LandmarkOptions l = StaticLandmark(1, 0.0, 0.0);
  l.motion.model = LandmarkMotionModel::kUnicycle;
  l.motion.v_mps = 0.5;
  o.landmarks = {l};
  auto more = o;
  l.id = 2;
  more.landmarks.push_back(l);
  World a(o), b(more);
  for (int k = 0; k < 10; ++k) {
    a.Step();
    b.Step();
  }
  EXPECT_EQ(a.Truth().landmarks[0].pose.x, b.Truth().landmarks[0].pose.x);
  EXPECT_EQ(a.Truth().landmarks[0].pose.heading, b.Truth().landmarks[0].pose.heading);
}

}  // namespace
}  // namespace mrslam::world_sim
