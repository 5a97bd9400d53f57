// FastSLAM's side of cooperation: merging a peer's map, leaving out landmarks beyond the position
// bound or too close to its own, copy-on-write sharing, observing a known robot.
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/LU>

#include "common/config/agent_options_projection.h"
#include "common/gaussian.h"
#include "robot_agent/cooperation/cooperation.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/fastslam.h"
#include "tests/robot_agent/tiny_world.h"

namespace mrslam::robot_agent::cooperation {
namespace {

// r1 (a FastSLAM agent) has mapped two static landmarks; r2 is a second robot of the scenario.
class WithFastSlam : public ::testing::TestWithParam<robot_agent::LandmarkKinematics> {
 protected:
  void SetUp() override {
    options_ = testing::OneRobotScenario(0.2, 0.0, 100);
    options_.filter.landmark_kinematics = GetParam();
    options_.filter.known_kinematics = {{0.0, 0.0}, {0.4, 0.2}};
    testing::AddLandmark(&options_, 1, {2.0, 0.5, 0.0});
    testing::AddLandmark(&options_, 2, {0.5, 2.0, 0.0});
    common::RobotOptions r2;
    r2.id = "r2";
    r2.frame_in_world = {1.0, 1.0, 0.5};
    options_.robots.push_back(r2);
    options_.rendezvous.enable_from_step = 0;
    filter_ = factory::CreateFilter(common::AgentOptionsFor(options_, "r1"), 3);
    testing::TinyWorld world(options_, 3);
    for (int k = 0; k < 8; ++k) filter_->Process(world.Step());
    ASSERT_EQ(filter_->Estimate().landmarks.size(), 2u);
  }

  // Lets r1's agent learn r2's frame from one mutual detection at step 8 (the filter's step).
  void Meet(Cooperation* agent) {
    const filters::FilterEstimate e = filter_->Estimate();
    common::LidarScan scan;
    scan.stamp = {"r1", e.step, e.time_s};
    scan.robots.push_back({e.time_s, 2.0, 0.3, "r2"});
    common::SensorStep step;
    step.lidar = scan;
    agent->AfterStep(step, e);
    RelativeMeasurement m;
    m.header = {"r2", "r1", e.step, e.time_s, 1};
    m.range_m = 2.0;
    m.bearing_rad = -0.4;
    m.sender_pose = {0.5, 0.5, 0.1};
    m.sender_covariance = Eigen::Matrix3d::Identity() * 1e-3;
    agent->Receive({{m}, {}, {}, {}}, filter_.get());
    ASSERT_EQ(agent->frames_known(), std::vector<std::string>{"r2"});
  }

  common::ScenarioOptions options_;
  std::unique_ptr<filters::SlamFilter> filter_;
};

// Particles of a FastSLAM filter (of any state dimension) holding more than n landmarks, and
// the number of particles.
template <int D>
const filters::FastSlam<D>* AsFastSlam(const filters::SlamFilter& f) {
  return dynamic_cast<const filters::FastSlam<D>*>(&f);
}
int ParticlesHoldingMoreThan(const filters::SlamFilter& f, int n) {
  int out = 0;
  const auto count = [&](const auto* fast) {
    for (int p = 0; fast != nullptr && p < fast->NumParticles(); ++p) out += fast->ParticleLandmarkCount(p) > n ? 1 : 0;
  };
  count(AsFastSlam<2>(f));
  count(AsFastSlam<3>(f));
  count(AsFastSlam<5>(f));
  return out;
}
int NumParticlesOf(const filters::SlamFilter& f) { return f.Estimate().particles; }

void ExpectSameEstimate(const filters::FilterEstimate& a, const filters::FilterEstimate& b) {
  EXPECT_EQ(a.pose.Vector(), b.pose.Vector());
  ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
  for (std::size_t i = 0; i < a.landmarks.size(); ++i) {
    EXPECT_EQ(a.landmarks[i].track_id, b.landmarks[i].track_id);
    EXPECT_EQ(a.landmarks[i].mean, b.landmarks[i].mean);
    EXPECT_EQ(a.landmarks[i].covariance, b.landmarks[i].covariance);
  }
}

TEST_P(WithFastSlam, MergeFusesMatchedAndAddsNewLandmarks) {
  const filters::FilterEstimate before = filter_->Estimate();
  std::vector<filters::MapLandmark> in(2);
  // The first landmark as a peer with the same knowledge would hold it.
  in[0].mean = before.landmarks[0].mean;
  in[0].covariance = before.landmarks[0].covariance;
  in[1].mean = {-3.0, -2.0, 0.0};  // a landmark this robot never saw
  in[1].covariance = Eigen::Vector3d(0.01, 0.01, 3.0).asDiagonal();
  const int added = filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.0);
  if (GetParam() == robot_agent::LandmarkKinematics::kConstantTurnRate) {
    // Each particle gates with its own landmark covariance, which is tight where the particle
    // takes the landmark as static: a particle far out in the mixture may take the first as new.
    EXPECT_GE(added, 1);
    EXPECT_LE(ParticlesHoldingMoreThan(*filter_, 3), NumParticlesOf(*filter_) / 20);
  } else {
    EXPECT_EQ(added, 1);
  }
  const filters::FilterEstimate after = filter_->Estimate();
  ASSERT_EQ(after.landmarks.size(), 3u);
  int near_new = 0;
  for (const auto& l : after.landmarks) {
    if ((l.mean.head<2>() - Eigen::Vector2d(-3.0, -2.0)).norm() < 1e-9) ++near_new;
    EXPECT_FALSE(l.tentative);
  }
  EXPECT_EQ(near_new, 1);
  // The matched landmark's covariance does not grow (CI: no larger determinant than either).
  for (const auto& b : before.landmarks) {
    for (const auto& a : after.landmarks) {
      if (a.track_id != b.track_id) continue;
      const double det_after = a.covariance.topLeftCorner<2, 2>().determinant();
      const double det_before = b.covariance.topLeftCorner<2, 2>().determinant();
      EXPECT_LE(det_after, det_before * (1.0 + 1e-9));
    }
  }
  // SLAM goes on with the merged map.
  testing::TinyWorld world(options_, 4);
  for (int k = 0; k < 3; ++k) filter_->Process(world.Step());
  EXPECT_GE(filter_->Estimate().landmarks.size(), 2u);
}

// filter.max_landmark_position_sd_m (default 2 m): a peer landmark already less certain than the
// bound is not merged; a merged one within it stays while its covariance does; one whose
// covariance grows past the bound unseen (a landmark with a motion model, out of view) leaves
// the map, as an own landmark would.
TEST_P(WithFastSlam, LandmarksBeyondThePositionSdBoundLeaveTheMap) {
  ASSERT_EQ(options_.filter.max_landmark_position_sd_m, 2.0);
  const auto count_near = [](const filters::FilterEstimate& e, const Eigen::Vector2d& at) {
    int n = 0;
    for (const auto& l : e.landmarks) n += (l.mean.head<2>() - at).norm() < 1.0 ? 1 : 0;
    return n;
  };
  const Eigen::Vector2d far(-20.0, -20.0), farther(-30.0, 20.0);  // out of view, unmatched
  const Eigen::Vector2d still(20.0, -20.0);                       // the same, static for the peer
  // The first two with the filter's motion model, as a peer of the same scenario reports them.
  const filters::LandmarkMotionKind kind = GetParam() == robot_agent::LandmarkKinematics::kStatic
                                               ? filters::LandmarkMotionKind::kStatic
                                           : GetParam() == robot_agent::LandmarkKinematics::kKnownCandidates
                                               ? filters::LandmarkMotionKind::kUnicycle
                                               : filters::LandmarkMotionKind::kConstantTurnRate;
  std::vector<filters::MapLandmark> in(3);
  in[0].mean = {far.x(), far.y(), 0.0};
  in[0].covariance = Eigen::Vector3d(1.9, 1.9, 3.0).asDiagonal();  // sd sqrt(3.8) < 2 m
  in[0].motion = kind;
  in[1].mean = {farther.x(), farther.y(), 0.0};
  in[1].covariance = Eigen::Vector3d(2.1, 2.1, 3.0).asDiagonal();  // sd sqrt(4.2) > 2 m
  in[1].motion = kind;
  in[2].mean = {still.x(), still.y(), 0.0};
  in[2].covariance = Eigen::Vector3d(1.9, 1.9, 0.01).asDiagonal();
  in[2].v_mps = 0.3;  // a static report whose mixture still carries a heading and a speed
  in[2].motion = filters::LandmarkMotionKind::kStatic;
  EXPECT_EQ(filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.0), 2);
  EXPECT_EQ(count_near(filter_->Estimate(), far), 1);
  EXPECT_EQ(count_near(filter_->Estimate(), farther), 0);
  EXPECT_EQ(count_near(filter_->Estimate(), still), 1);
  testing::TinyWorld world(options_, 5);
  for (int k = 0; k < 10; ++k) filter_->Process(world.Step());
  const filters::FilterEstimate after = filter_->Estimate();
  // Static landmarks keep their covariance when unseen; a motion model spreads it every step. A
  // constant-turn-rate filter keeps a landmark the peer takes as static static; known
  // candidates have no static model.
  EXPECT_EQ(count_near(after, far), GetParam() == robot_agent::LandmarkKinematics::kStatic ? 1 : 0);
  EXPECT_EQ(count_near(after, still), GetParam() == robot_agent::LandmarkKinematics::kKnownCandidates ? 0 : 1);
  for (const auto& l : after.landmarks) {
    const double position_variance = l.covariance(0, 0) + l.covariance(1, 1);
    EXPECT_LE(position_variance, 4.0 + 1e-9);
  }
}

// cooperation.merge_min_separation_m: a static peer landmark outside the gate of the static own
// one it lies next to is left out, not added as a second copy; farther off, it is added. Next to
// a moving landmark (known candidates here) it is added: moving landmarks pass close by others.
TEST_P(WithFastSlam, MergeLeavesOutPeerLandmarksTooCloseToOwnOnes) {
  if (GetParam() == robot_agent::LandmarkKinematics::kConstantTurnRate) {
    GTEST_SKIP() << "whether the own landmark is static differs from particle to particle";
  }
  const filters::FilterEstimate before = filter_->Estimate();
  ASSERT_FALSE(before.landmarks.empty());
  std::vector<filters::MapLandmark> in(1);
  in[0].mean = before.landmarks[0].mean + Eigen::Vector3d(1.0, 0.0, 0.0);
  in[0].covariance = Eigen::Vector3d(1e-4, 1e-4, 3.0).asDiagonal();  // 1 m off, far beyond the gate
  in[0].motion = filters::LandmarkMotionKind::kStatic;
  const int added = filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 1.5);
  if (GetParam() == robot_agent::LandmarkKinematics::kKnownCandidates) {
    EXPECT_EQ(added, 1);
    return;
  }
  EXPECT_EQ(added, 0);
  ExpectSameEstimate(filter_->Estimate(), before);
  EXPECT_EQ(filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.5), 1);
  EXPECT_EQ(filter_->Estimate().landmarks.size(), before.landmarks.size() + 1);
}

TEST_P(WithFastSlam, MergeKeepsCopyOnWriteSharing) {
  auto* fast = dynamic_cast<filters::FastSlam<2>*>(filter_.get());
  if (fast == nullptr) GTEST_SKIP() << "checked on the static instantiation";
  std::vector<filters::MapLandmark> in(1);
  in[0].mean = {-3.0, -2.0, 0.0};
  in[0].covariance = Eigen::Vector3d(0.01, 0.01, 3.0).asDiagonal();
  filter_->MergeLandmarks(in, robot_agent::MapFusionRule::kWeighted, 0.999, 0.0);
  // Blocks are never shared by two particles after one of them wrote (each particle's storage
  // addresses are its own where it wrote); every particle holds the added landmark.
  for (int p = 0; p < fast->NumParticles(); ++p) EXPECT_EQ(fast->ParticleLandmarkCount(p), 3);
}

TEST_P(WithFastSlam, RejectedSnapshotsLeaveTheEstimateUnchanged) {
  Cooperation agent(common::AgentOptionsFor(options_, "r1"));
  Meet(&agent);
  const filters::FilterEstimate before = filter_->Estimate();
  MapSnapshot good;
  good.header = {"r2", "r1", before.step, before.time_s, 2};
  filters::MapLandmark l;
  l.mean = {-3.0, -3.0, 0.0};  // far from the own landmarks: added
  l.covariance = Eigen::Vector3d(0.01, 0.01, 3.0).asDiagonal();
  good.landmarks.push_back(l);
  MapSnapshot nan = good;
  nan.landmarks[0].mean.y() = std::nan("");
  MapSnapshot not_pd = good;
  not_pd.landmarks[0].covariance(1, 1) = -1.0;
  MapSnapshot too_big = good;
  too_big.landmarks.assign(300, l);
  MapSnapshot unknown = good;
  unknown.header.sender = "r5";
  agent.Receive({{}, {nan, not_pd, too_big, unknown}, {}, {}}, filter_.get());
  EXPECT_EQ(agent.rejected_messages(), 4);
  ExpectSameEstimate(filter_->Estimate(), before);
  agent.Receive({{}, {good}, {}, {}}, filter_.get());
  EXPECT_EQ(agent.rejected_messages(), 4);
  EXPECT_EQ(filter_->Estimate().landmarks.size(), before.landmarks.size() + 1);
}

TEST_P(WithFastSlam, ObservingAKnownRobotReweightsParticles) {
  auto* fast = dynamic_cast<filters::FastSlam<2>*>(filter_.get());
  if (fast == nullptr) GTEST_SKIP() << "checked on the static instantiation";
  // A robot 2 m ahead of the mean pose: particles that agree gain weight.
  const filters::FilterEstimate e = filter_->Estimate();
  const Eigen::Vector2d there = common::PointFromRangeBearing(e.pose, {2.0, 0.0});
  const double gate = common::ChiSquare2Quantile(0.9999);
  ASSERT_TRUE(filter_->ObserveKnownRobot(there, Eigen::Matrix2d::Identity() * 1e-4, 2.0, 0.0, gate));
  double sum = 0.0;
  std::vector<double> weights;
  for (int p = 0; p < fast->NumParticles(); ++p) {
    weights.push_back(fast->ParticleWeight(p));
    sum += weights.back();
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);
  // A detection 3 m off where the robot is said to be is an outlier: not used,
  // the weights stay as they are.
  EXPECT_FALSE(filter_->ObserveKnownRobot(there, Eigen::Matrix2d::Identity() * 1e-4, 5.0, 0.0, gate));
  for (int p = 0; p < fast->NumParticles(); ++p) EXPECT_EQ(fast->ParticleWeight(p), weights[p]);
}

INSTANTIATE_TEST_SUITE_P(Kinematics, WithFastSlam,
                         ::testing::Values(robot_agent::LandmarkKinematics::kStatic,
                                           robot_agent::LandmarkKinematics::kKnownCandidates,
                                           robot_agent::LandmarkKinematics::kConstantTurnRate));

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
