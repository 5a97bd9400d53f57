#include "robot_agent/filters/reachable_landmarks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "common/rng.h"
#include "common/se2.h"
#include "robot_agent/filters/association.h"

namespace mrslam::robot_agent::filters {
namespace {

constexpr double kVarR = 0.0025, kVarB = 0.0004;
constexpr double kGate = 13.8;  // chi-square, 2 dof, 0.999

ReachRule Rule(bool euclidean) { return {euclidean ? 0.09 : kGate, kVarR, kVarB, euclidean, 0.25}; }

Eigen::Matrix3d RandomPoseCovariance(common::Rng* rng, double scale) {
  Eigen::Matrix3d a;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) a(i, j) = rng->Normal(0.0, std::sqrt(scale));
  }
  return a * a.transpose();
}

// A block of kLanes landmarks of state dimension 5 within `spread` m of (0, 0).
LandmarkBlock<5> RandomBlock(common::Rng* rng, double spread) {
  LandmarkBlock<5> block;
  for (int l = 0; l < kLanes; ++l) {
    StateVector<5> m = StateVector<5>::Zero();
    m(0) = rng->Uniform(-spread, spread);
    m(1) = rng->Uniform(-spread, spread);
    StateMatrix<5> a;
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) a(i, j) = rng->Normal(0.0, 0.2);
    }
    block.Set(l, m, a * a.transpose() + 1e-3 * StateMatrix<5>::Identity());
  }
  return block;
}

// A reading of landmark `lane` of the block from pose, its range and bearing perturbed so that
// the landmarks' gate distances spread on both sides of the gate.
Eigen::Vector2d NoisyReading(const LandmarkBlock<5>& block, int lane, const common::Pose2& pose, common::Rng* rng) {
  const common::RangeBearing z =
      common::MeasureRangeBearing(pose, Eigen::Vector2d(block.Mean(0, lane), block.Mean(1, lane)));
  return {std::max(0.05, z.range_m + rng->Normal(0.0, 0.6)), z.bearing_rad + rng->Normal(0.0, 0.1)};
}

// Every landmark that GateBlock puts within the gate, from any pose within the shift of the
// gathering point and with no more position variance, is among the reachable lanes; and the
// lanes left out are many.
TEST(ReachableLanes, KeepsEveryLandmarkWithinTheGate) {
  common::Rng rng(11, "reachable_lanes");
  for (const bool euclidean : {false, true}) {
    const ReachRule rule = Rule(euclidean);
    int within = 0, left_out = 0;
    for (int t = 0; t < 4000; ++t) {
      const LandmarkBlock<5> block = RandomBlock(&rng, 12.0);
      const Eigen::Vector2d center(rng.Uniform(-1.0, 1.0), rng.Uniform(-1.0, 1.0));
      const Eigen::Matrix3d gathered = RandomPoseCovariance(&rng, 0.01);
      const double angle = rng.Uniform(-common::kPi, common::kPi), shift = rng.Uniform(0.0, rule.shift_m);
      const common::Pose2 pose{center.x() + shift * std::cos(angle), center.y() + shift * std::sin(angle),
                               rng.Uniform(-common::kPi, common::kPi)};
      const Eigen::Matrix3d sigma = rng.Uniform(0.0, 1.0) * gathered;
      const Eigen::Vector2d z = NoisyReading(block, t % kLanes, pose, &rng);
      const std::uint32_t lanes =
          ReachableLanes(block, kLanes, center, gathered(0, 0) + gathered(1, 1), z(0), z(0), rule);
      double d2[kLanes];
      GateBlock(block, kLanes, pose, sigma, z(0), z(1), kVarR, kVarB, euclidean, d2);
      for (int l = 0; l < kLanes; ++l) {
        const bool reachable = (lanes >> l) & 1U;
        if (d2[l] <= rule.gate) {
          ++within;
          EXPECT_TRUE(reachable) << "trial " << t << " lane " << l << " d2 " << d2[l];
        }
        if (!reachable) ++left_out;
      }
    }
    EXPECT_GT(within, 1000) << "euclidean " << euclidean;
    EXPECT_GT(left_out, 4000 * kLanes / 2) << "euclidean " << euclidean;
  }
}

// A landmark whose range is not a number is kept, as gating every landmark would meet it.
TEST(ReachableLanes, KeepsALandmarkOfNoNumber) {
  LandmarkBlock<5> block;
  block.Set(0, StateVector<5>::Constant(std::numeric_limits<double>::quiet_NaN()), StateMatrix<5>::Identity());
  block.Set(1, StateVector<5>::Constant(100.0), 1e-4 * StateMatrix<5>::Identity());
  EXPECT_EQ(ReachableLanes(block, 2, Eigen::Vector2d::Zero(), 0.0, 1.0, 6.0, Rule(false)), 1U);
}

// Over a particle's many blocks and a sequence of readings from a proposal that moves (beyond
// the shift: gathered again) and shrinks, with slots used as readings take them: the nearest
// unused landmark and its distance are those of gating every landmark whenever it is within
// the gate, and beyond the gate whenever it is not.
TEST(ReachableLandmarks, NearestIsGatingEveryLandmarkWithinTheGate) {
  common::Rng rng(12, "reachable_landmarks");
  const ReachRule rule = Rule(false);
  int matched = 0;
  for (int t = 0; t < 200; ++t) {
    const int count = 1 + static_cast<int>(rng.Uniform(0.0, 6.0 * kLanes));
    std::vector<std::shared_ptr<LandmarkBlock<5>>> blocks;
    for (int b = 0; b * kLanes < count; ++b)
      blocks.push_back(std::make_shared<LandmarkBlock<5>>(RandomBlock(&rng, 15.0)));
    std::vector<std::uint8_t> used(count, 0);
    ReachableLandmarks<5> reachable(rule);
    reachable.StartStep(0.5, 6.0);
    common::Pose2 pose{rng.Uniform(-2.0, 2.0), rng.Uniform(-2.0, 2.0), rng.Uniform(-common::kPi, common::kPi)};
    Eigen::Matrix3d sigma = RandomPoseCovariance(&rng, 0.01);
    for (int k = 0; k < 6; ++k) {
      const int slot = static_cast<int>(rng.Uniform(0.0, count - 1e-9));
      Eigen::Vector2d z = NoisyReading(*blocks[slot / kLanes], slot % kLanes, pose, &rng);
      z(0) = std::clamp(z(0), 0.5, 6.0);
      std::vector<double> all(blocks.size() * kLanes);
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        GateBlock(*blocks[b], std::min(kLanes, count - static_cast<int>(b) * kLanes), pose, sigma, z(0), z(1), kVarR,
                  kVarB, false, &all[b * kLanes]);
      }
      const int expected = NearestUnused(all.data(), count, used);
      const auto [got, d2] = reachable.Nearest(blocks, count, pose, sigma, z(0), z(1), used);
      if (expected >= 0 && all[expected] <= rule.gate) {
        ++matched;
        EXPECT_EQ(got, expected) << "trial " << t << " reading " << k;
        EXPECT_EQ(d2, all[expected]);
        used[expected] = 1;
      } else {
        EXPECT_GT(d2, rule.gate) << "trial " << t << " reading " << k;
      }
      EXPECT_LE(reachable.size(), count);
      pose.x += rng.Uniform(-0.2, 0.2);
      pose.y += rng.Uniform(-0.2, 0.2);
      sigma *= 0.8;
    }
  }
  EXPECT_GT(matched, 200);
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
