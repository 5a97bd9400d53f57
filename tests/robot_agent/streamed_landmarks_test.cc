// Peers' landmarks streamed with their raw measurements (StreamedLandmarks): placed in the own
// frame through the transform held, a mover predicted as the smoother predicts its own, and not
// shown where the robot's lidar has reached, where its map holds one too close, or when placed so
// loosely that the robot could not check it.
#include "robot_agent/cooperation/streamed_landmarks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace mrslam::robot_agent::cooperation {
namespace {

AgentOptions Options(LandmarkKinematics kinematics = LandmarkKinematics::kConstantTurnRate) {
  AgentOptions o;
  o.robot_id = "a";
  o.team = {"a", "b"};
  o.dt_s = 0.5;
  o.sensors.lidar.max_range_m = 6.0;
  o.filter.landmark_kinematics = kinematics;
  o.filter.smoother.mover_memory_s = 1.0;
  o.cooperation.share_factors = true;
  o.cooperation.merge_min_separation_m = 1.5;
  return o;
}

// b's log: steps 1..5 (0.5 s apart), its estimate of label 3 made at step 5.
FactorLog Log(const Eigen::Vector3d& mean, bool moving = false, double v_mps = 0.0) {
  FactorLog log;
  for (std::uint32_t k = 1; k <= 5; ++k) {
    common::SensorStep s;
    s.lidar.stamp = {"b", k, 0.5 * k};
    log.steps.push_back(s);
  }
  TrackEstimate t;
  t.label = 3;
  t.step = 5;
  t.mean = mean;
  t.position_covariance = 0.01 * Eigen::Matrix2d::Identity();
  t.heading_var = 0.01;
  t.v_mps = v_mps;
  t.moving = moving;
  log.tracks[3] = t;
  return log;
}

// T(G_a <- G_b): a shift by (1, 2), no rotation, well known.
std::vector<FrameTransform> Frames() { return {{"b", 1, {1.0, 2.0, 0.0}, 1e-4 * Eigen::Matrix3d::Identity()}}; }

filters::FilterEstimate At(const common::Pose2& pose, double time_s) {
  filters::FilterEstimate e;
  e.step = 5;
  e.time_s = time_s;
  e.pose = pose;
  e.covariance = 1e-4 * Eigen::Matrix3d::Identity();
  return e;
}

std::vector<filters::MapLandmark> Shown(const StreamedLandmarks& s, const std::map<std::string, FactorLog>& logs,
                                        filters::FilterEstimate e) {
  s.Append(logs, Frames(), &e);
  return e.landmarks;
}

TEST(StreamedLandmarks, APeersLandmarkIsPlacedThroughTheTransformWithItsProvenance) {
  StreamedLandmarks s(Options());
  const std::map<std::string, FactorLog> logs{{"b", Log({20.0, 0.0, 0.0})}};
  const auto shown = Shown(s, logs, At({0.0, 0.0, 0.0}, 2.5));
  ASSERT_EQ(shown.size(), 1U);
  EXPECT_NEAR(shown[0].mean.x(), 21.0, 1e-12);
  EXPECT_NEAR(shown[0].mean.y(), 2.0, 1e-12);
  EXPECT_GT(shown[0].covariance(0, 0), 0.01);  // the transform's covariance added
  EXPECT_EQ(shown[0].origin_robot, 1);
  EXPECT_EQ(shown[0].origin_track, 3U);
  EXPECT_EQ(shown[0].track_id, StreamedLandmarks::kFirstTrack | (1U << 20) | 3U);
  EXPECT_FALSE(shown[0].moving);
}

TEST(StreamedLandmarks, NotShownWhereTheMapHoldsOneTooClose) {
  StreamedLandmarks s(Options());
  const std::map<std::string, FactorLog> logs{{"b", Log({20.0, 0.0, 0.0})}};
  filters::FilterEstimate e = At({0.0, 0.0, 0.0}, 2.5);
  e.landmarks.resize(1);
  e.landmarks[0].mean = {21.0, 3.2, 0.0};  // 1.2 m away
  EXPECT_EQ(Shown(s, logs, e).size(), 1U);
  e.landmarks[0].mean = {21.0, 3.7, 0.0};  // 1.7 m away: another landmark
  EXPECT_EQ(Shown(s, logs, e).size(), 2U);
}

TEST(StreamedLandmarks, NotShownWhereTheOwnLidarHasReached) {
  StreamedLandmarks s(Options());
  const std::map<std::string, FactorLog> logs{{"b", Log({20.0, 0.0, 0.0})}};
  s.Observe(At({12.0, 2.0, 0.0}, 2.5));  // 9 m away: out of reach
  EXPECT_EQ(Shown(s, logs, At({12.0, 2.0, 0.0}, 2.5)).size(), 1U);
  s.Observe(At({16.0, 2.0, 0.0}, 3.0));  // 5 m away: its own map stands there
  EXPECT_TRUE(Shown(s, logs, At({0.0, 0.0, 0.0}, 3.0)).empty());
}

TEST(StreamedLandmarks, NotShownWhenPlacedMoreLooselyThanTheLidarReaches) {
  StreamedLandmarks s(Options());
  FactorLog log = Log({20.0, 0.0, 0.0});
  log.tracks[3].position_covariance = 9.0 * Eigen::Matrix2d::Identity();  // 3 sd: 9 m > 6 m
  EXPECT_TRUE(Shown(s, {{"b", log}}, At({0.0, 0.0, 0.0}, 2.5)).empty());
}

TEST(StreamedLandmarks, AMoverIsPredictedAsTheSmootherPredictsItsOwn) {
  StreamedLandmarks s(Options());
  const std::map<std::string, FactorLog> logs{{"b", Log({20.0, 0.0, 0.0}, true, 0.4)}};
  const auto shown = Shown(s, logs, At({0.0, 0.0, 0.0}, 4.5));  // 2 s after its estimate
  ASSERT_EQ(shown.size(), 1U);
  EXPECT_TRUE(shown[0].moving);
  // Gauss-Markov velocity of correlation time 1 s: 0.4 (1 - e^-2) m along its heading.
  EXPECT_NEAR(shown[0].mean.x(), 21.0 + 0.4 * (1.0 - std::exp(-2.0)), 1e-9);
  EXPECT_NEAR(shown[0].mean.y(), 2.0, 1e-9);
  EXPECT_GT(shown[0].covariance(1, 1), 0.01 + 0.02);  // its spread over 2 s added
}

TEST(StreamedLandmarks, MoversAreNotShownAmongKnownKinematics) {
  StreamedLandmarks s(Options(LandmarkKinematics::kKnownCandidates));
  const std::map<std::string, FactorLog> logs{{"b", Log({20.0, 0.0, 0.0}, true, 0.4)}};
  EXPECT_TRUE(Shown(s, logs, At({0.0, 0.0, 0.0}, 4.5)).empty());
}

TEST(StreamedLandmarks, OnlyWhatReachedTheAgentAndOnlyPeersWithAKnownFrame) {
  StreamedLandmarks s(Options());
  FactorLog log = Log({20.0, 0.0, 0.0});
  log.tracks[3].step = 6;  // of a step not held
  EXPECT_TRUE(Shown(s, {{"b", log}}, At({0.0, 0.0, 0.0}, 2.5)).empty());
  filters::FilterEstimate e = At({0.0, 0.0, 0.0}, 2.5);
  s.Append({{"b", Log({20.0, 0.0, 0.0})}}, {}, &e);  // b's frame unknown
  EXPECT_TRUE(e.landmarks.empty());
}

TEST(StreamedLandmarks, ComesBackFromAnArchiveAsItWas) {
  StreamedLandmarks s(Options());
  s.Observe(At({16.0, 2.0, 0.0}, 3.0));
  common::Archive out = common::Archive::ForWriting();
  s.Io(out);
  StreamedLandmarks back(Options());
  common::Archive in = common::Archive::ForReading(out.bytes());
  back.Io(in);
  EXPECT_TRUE(in.AtEnd());
  EXPECT_EQ(back.Bytes(), s.Bytes());
  EXPECT_TRUE(Shown(back, {{"b", Log({20.0, 0.0, 0.0})}}, At({0.0, 0.0, 0.0}, 3.0)).empty());
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
