#include "robot_agent/smoother/online_smoother.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "tests/robot_agent/tiny_world.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::robot_agent::smoother {
namespace {

std::string Config(const std::string& name) { return std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/" + name; }

// Runs robot r1 of the scenario alone with the online smoother; returns its pose error (own
// frame) and pose NEES at every step.
struct Errors {
  std::vector<double> position_m, heading_rad, nees;
  int recoveries = 0;
};
Errors RunR1(const common::ScenarioOptions& o) {
  const auto source = world_sim::MakeStepSource(o);
  const common::Pose2 frame = source->Truth().frames.at(0).second;
  OnlineSmoother smoother(common::AgentOptionsFor(o, "r1"), o.seed);
  Errors e;
  for (int k = 0; k < o.run.steps; ++k) {
    smoother.Process(source->Step().at(0));
    const common::Pose2 truth = common::Compose(common::Inverse(frame), source->Truth().robots[0].pose);
    const auto estimate = smoother.Estimate();
    Eigen::Vector3d d = estimate.pose.Vector() - truth.Vector();
    d(2) = common::WrapAngle(d(2));
    e.position_m.push_back(d.head<2>().norm());
    e.heading_rad.push_back(std::abs(d(2)));
    e.nees.push_back(d.dot(estimate.covariance.ldlt().solve(d)));
  }
  e.recoveries = smoother.Recoveries();
  return e;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

TEST(OnlineSmoother, PoseNeesIsConsistentOverSeeds) {
  // paper_two_robots, r1 alone, seeds 1..8: the median over seeds of the run's mean pose NEES
  // (3 dof: 3 is ideal).
  std::vector<double> means;
  for (int seed = 1; seed <= 8; ++seed) {
    const auto o = common::LoadScenario(Config("paper_two_robots.yaml"), {"seed=" + std::to_string(seed)});
    const Errors e = RunR1(o);
    double sum = 0.0;
    for (const double n : e.nees) sum += n;
    means.push_back(sum / static_cast<double>(e.nees.size()));
  }
  EXPECT_GT(Median(means), 1.5);
  EXPECT_LT(Median(means), 6.0);
}

TEST(OnlineSmoother, FindsItsPoseAgainAfterASlip) {
  // r1 slides 1 m and turns 45 degrees at step 83 while its odometry reads nothing.
  const auto o = common::LoadScenario(Config("slip.yaml"), {"filter.type=smoother"});
  const Errors e = RunR1(o);
  EXPECT_GE(e.recoveries, 1);
  // Lost at first (steps 83..87 are entries 82..86).
  EXPECT_GT(*std::max_element(e.heading_rad.begin() + 82, e.heading_rad.begin() + 87), common::RadFromDeg(20.0));
  EXPECT_LT(e.position_m.back(), 0.3);
  EXPECT_LT(e.heading_rad.back(), common::RadFromDeg(5.0));
}

TEST(OnlineSmoother, SearchesAgainWhenTheFirstSearchFindsTooLittle) {
  // Seed 3: at the first search the view holds two mapped landmarks of four readings, too little
  // to take a pose; the next keyframe's view has three, and there the pose is found.
  const auto o = common::LoadScenario(Config("slip.yaml"), {"filter.type=smoother", "seed=3"});
  const Errors e = RunR1(o);
  EXPECT_EQ(e.recoveries, 1);
  EXPECT_GT(*std::max_element(e.heading_rad.begin() + 82, e.heading_rad.begin() + 87), common::RadFromDeg(20.0));
  EXPECT_LT(e.position_m.back(), 0.3);
  EXPECT_LT(e.heading_rad.back(), common::RadFromDeg(5.0));
}

// What the smoother holds grows with the keyframes it marginalizes, each kept whole in the fixed
// history for the final trajectory, and with little else once its map is complete. Eight static
// landmarks around a circle (every step a keyframe: one step of one odometry segment and the
// readings of at most the eight landmarks): from step 200 to step 2000, EstimatorBytes grows by
// between KeyframeBytes(1, 1, 0) and KeyframeBytes(1, 1, 8) per keyframe marginalized.
TEST(OnlineSmoother, EstimatorBytesGrowByTheKeyframesMarginalized) {
  common::ScenarioOptions o = testing::OneRobotScenario(1.0, 0.2, 100);
  o.robots[0].initial_pose = {0.0, -5.0, 0.0};
  for (int i = 0; i < 8; ++i) {
    const double a = i * common::kPi / 4.0;
    testing::AddLandmark(&o, i + 1, {(i % 2 ? 3.0 : 7.0) * std::cos(a), (i % 2 ? 3.0 : 7.0) * std::sin(a), 0.0});
  }
  o.filter.landmark_kinematics = LandmarkKinematics::kStatic;
  testing::TinyWorld world(o, 3);
  OnlineSmoother smoother(common::AgentOptionsFor(o, "r1"), 3);
  std::size_t bytes_200 = 0;
  int history_200 = 0;
  for (int k = 1; k <= 2000; ++k) {
    smoother.Process(world.Step());
    if (k == 200) {
      bytes_200 = smoother.EstimatorBytes();
      history_200 = smoother.Graph().HistorySize();
    }
  }
  const int marginalized = smoother.Graph().HistorySize() - history_200;
  EXPECT_EQ(marginalized, 1800);
  const double per_keyframe =
      (static_cast<double>(smoother.EstimatorBytes()) - static_cast<double>(bytes_200)) / marginalized;
  EXPECT_GE(per_keyframe, static_cast<double>(KeyframeGraph::KeyframeBytes(1, 1, 0)));
  EXPECT_LE(per_keyframe, static_cast<double>(KeyframeGraph::KeyframeBytes(1, 1, 8)));
}

// A peer's landmarks are shown beside the own map and never enter the estimate: the pose stays
// as it is without them. One where the robot has already looked is not taken (its own map stands
// there); one it comes to see where its lidar sees nothing is let go; one out of its sight stays.
TEST(OnlineSmoother, PeersLandmarksAreShownButDoNotMoveTheEstimate) {
  common::ScenarioOptions o = testing::OneRobotScenario(1.0, 0.2, 100);
  o.robots[0].initial_pose = {0.0, -5.0, 0.0};  // a circle of radius 5 about the origin, 0.1 rad a step
  for (int i = 0; i < 8; ++i) {
    const double a = i * common::kPi / 4.0;
    testing::AddLandmark(&o, i + 1, {(i % 2 ? 3.0 : 7.0) * std::cos(a), (i % 2 ? 3.0 : 7.0) * std::sin(a), 0.0});
  }
  o.filter.landmark_kinematics = LandmarkKinematics::kStatic;
  const AgentOptions options = common::AgentOptionsFor(o, "r1");
  testing::TinyWorld world(o, 3);
  OnlineSmoother alone(options, 3), sharing(options, 3);
  const auto peer_landmark = [](double x, double y) {
    filters::MapLandmark l;
    l.mean = {x, y, 0.0};
    l.covariance = 0.01 * Eigen::Matrix3d::Identity();
    l.origin_robot = 1;
    return l;
  };
  const auto shown = [](const filters::FilterEstimate& e, const Eigen::Vector2d& p) {
    return std::any_of(e.landmarks.begin(), e.landmarks.end(), [&](const filters::MapLandmark& l) {
      return l.track_id >= PeerLandmarks::kFirstTrack && (l.mean.head<2>() - p).norm() < 1e-9;
    });
  };
  const Eigen::Vector2d centre(0.0, 0.0), ahead(-9.0, 0.0), far(40.0, 40.0);
  for (int k = 1; k <= 100; ++k) {
    const common::SensorStep step = world.Step();
    alone.Process(step);
    sharing.Process(step);
    if (k == 20) {
      // The centre has been well inside the view from the start; (-9, 0) comes into it about
      // step 45 (nothing stands there); (40, 40) never does.
      const std::vector<filters::MapLandmark> peer = {
          peer_landmark(centre.x(), centre.y()), peer_landmark(ahead.x(), ahead.y()), peer_landmark(far.x(), far.y())};
      EXPECT_EQ(sharing.MergeLandmarks(peer, MapFusionRule::kCovarianceIntersection, 0.999, 1.5), 2);
      EXPECT_FALSE(shown(sharing.Estimate(), centre));
      EXPECT_TRUE(shown(sharing.Estimate(), ahead));
    }
    const filters::FilterEstimate a = alone.Estimate(), s = sharing.Estimate();
    ASSERT_EQ(a.pose.Vector(), s.pose.Vector()) << "step " << k;
    ASSERT_EQ(a.covariance, s.covariance) << "step " << k;
  }
  EXPECT_FALSE(shown(sharing.Estimate(), ahead));
  EXPECT_TRUE(shown(sharing.Estimate(), far));
  EXPECT_EQ(PeerLandmarks::MissesToDrop(1.0), 2);
  EXPECT_EQ(PeerLandmarks::MissesToDrop(0.9), 3);
  EXPECT_EQ(PeerLandmarks::MissesToDrop(0.5), 10);
}

// swarm_8, r1 alone: a mover out of sight is shown where it slows to a stop (MoverMemory) instead
// of where its last (v, w) would take it. The estimate is the same at every step; the map's moving
// entries that stand for nothing (3 m or more from every true landmark, scored as ghosts) are
// fewer, and the others nearer their landmarks.
TEST(OnlineSmoother, MoversOutOfSightAreNotExtrapolatedAway) {
  struct Score {
    int ghosts = 0, placed = 0;
    double error_m = 0.0;
  } kept_score, extrapolated_score;
  for (int seed = 1; seed <= 2; ++seed) {
    const auto o = common::LoadScenario(Config("swarm_8.yaml"), {"seed=" + std::to_string(seed)});
    const auto off = common::LoadScenario(Config("swarm_8.yaml"),
                                          {"seed=" + std::to_string(seed), "filter.smoother.mover_memory_s=0"});
    const auto source = world_sim::MakeStepSource(o);
    const common::Pose2 frame = source->Truth().frames.at(0).second;
    OnlineSmoother kept(common::AgentOptionsFor(o, "r1"), o.seed),
        extrapolated(common::AgentOptionsFor(off, "r1"), o.seed);
    // Over the moving entries of a map: those 3 m or more from every true landmark, and the
    // others' distance to their nearest.
    const auto add = [&](const filters::FilterEstimate& e, Score* score) {
      for (const filters::MapLandmark& l : e.landmarks) {
        if (!l.moving) continue;
        const Eigen::Vector2d p = common::TransformPoint(frame, l.mean.head<2>());
        double nearest = 3.0;
        for (const auto& t : source->Truth().landmarks) nearest = std::min(nearest, (t.pose.Translation() - p).norm());
        if (nearest >= 3.0) {
          ++score->ghosts;
        } else {
          ++score->placed;
          score->error_m += nearest;
        }
      }
    };
    for (int k = 0; k < o.run.steps; ++k) {
      const common::SensorStep step = source->Step().at(0);
      kept.Process(step);
      extrapolated.Process(step);
      const filters::FilterEstimate a = kept.Estimate(), b = extrapolated.Estimate();
      ASSERT_EQ(a.pose.Vector(), b.pose.Vector()) << "seed " << seed << " step " << k;
      ASSERT_EQ(a.covariance, b.covariance) << "seed " << seed << " step " << k;
      add(a, &kept_score);
      add(b, &extrapolated_score);
    }
  }
  EXPECT_LT(kept_score.ghosts, extrapolated_score.ghosts);
  ASSERT_GT(kept_score.placed, 0);
  ASSERT_GT(extrapolated_score.placed, 0);
  EXPECT_LT(kept_score.error_m / kept_score.placed, extrapolated_score.error_m / extrapolated_score.placed);
}

TEST(OnlineSmoother, AMoversKnownKinematicsAreTheOnesItsReadingsSupport) {
  // Paper A's world, r1 alone, a front end of two particles (which settle on one candidate for
  // each landmark within a few steps, often the wrong one): at the end every mover the map holds
  // has the speed of the true landmark it stands for.
  int right = 0, wrong = 0;
  for (int seed = 1; seed <= 6; ++seed) {
    const auto o = common::LoadScenario(Config("paper_two_robots.yaml"),
                                        {"seed=" + std::to_string(seed), "filter.type=smoother",
                                         "filter.smoother.front_end_particles=2", "run.steps=40"});
    const auto source = world_sim::MakeStepSource(o);
    const common::Pose2 frame = source->Truth().frames.at(0).second;
    OnlineSmoother smoother(common::AgentOptionsFor(o, "r1"), o.seed);
    for (int k = 0; k < o.run.steps; ++k) smoother.Process(source->Step().at(0));
    for (const filters::MapLandmark& l : smoother.Estimate().landmarks) {
      if (!l.moving) continue;
      const Eigen::Vector2d p = common::TransformPoint(frame, l.mean.head<2>());
      const auto& truth = source->Truth().landmarks;
      const auto nearest = std::min_element(truth.begin(), truth.end(), [&](const auto& a, const auto& b) {
        return (a.pose.Translation() - p).norm() < (b.pose.Translation() - p).norm();
      });
      const double true_speed = o.landmarks.at(static_cast<std::size_t>(nearest - truth.begin())).motion.v_mps;
      (std::abs(l.v_mps - true_speed) < 1e-9 ? right : wrong) += 1;
    }
  }
  EXPECT_GE(right, 10);
  EXPECT_EQ(wrong, 0);
}

// The true landmark nearest to where a reading of robot `robot` puts its point from its true pose.
int TrueLandmarkOf(const common::GroundTruth& truth, std::size_t robot, const common::LandmarkDetection& z) {
  const Eigen::Vector2d p = common::PointFromRangeBearing(truth.robots.at(robot).pose, {z.range_m, z.bearing_rad});
  const auto nearest =
      std::min_element(truth.landmarks.begin(), truth.landmarks.end(), [&](const auto& a, const auto& b) {
        return (a.pose.Translation() - p).norm() < (b.pose.Translation() - p).norm();
      });
  return static_cast<int>(nearest - truth.landmarks.begin());
}

TEST(OnlineSmoother, AMoverMappedAgainUnderANewTrackContinuesTheChainOfTheSameLandmark) {
  // Paper A's world, r1 alone, seeds in which the front end loses a mover and maps it again: the
  // new track is joined to the graph's chain of the old one, and the readings of both tracks are
  // of the same true landmark (each reading's: the one nearest its point from the true pose).
  int joins = 0;
  for (const int seed : {17, 26, 48}) {
    const auto o =
        common::LoadScenario(Config("paper_two_robots.yaml"), {"seed=" + std::to_string(seed), "filter.type=smoother"});
    const auto source = world_sim::MakeStepSource(o);
    OnlineSmoother smoother(common::AgentOptionsFor(o, "r1"), o.seed);
    std::map<std::uint32_t, std::map<int, int>> landmarks_of_track;  // readings per true landmark
    for (int k = 0; k < o.run.steps; ++k) {
      const common::SensorStep step = source->Step().at(0);
      smoother.Process(step);
      const std::vector<std::uint32_t>& tracks = smoother.Estimate().detection_tracks;
      for (std::size_t i = 0; i < step.lidar.landmarks.size() && i < tracks.size(); ++i) {
        if (tracks[i] != 0)
          ++landmarks_of_track[tracks[i]][TrueLandmarkOf(source->Truth(), 0, step.lidar.landmarks[i])];
      }
    }
    const auto most_read = [&](std::uint32_t track) {
      const auto& counts = landmarks_of_track[track];
      return std::max_element(counts.begin(), counts.end(),
                              [](const auto& a, const auto& b) { return a.second < b.second; })
          ->first;
    };
    for (const auto& [track, chain] : smoother.Joined()) {
      ASSERT_FALSE(landmarks_of_track[track].empty()) << seed;
      ASSERT_FALSE(landmarks_of_track[chain].empty()) << seed;
      EXPECT_EQ(most_read(track), most_read(chain)) << "seed " << seed << ": track " << track << " joined to " << chain;
      EXPECT_EQ(smoother.Graph().ChainStates(track), 0) << seed;
      ++joins;
    }
  }
  EXPECT_GE(joins, 3);
}

TEST(OnlineSmoother, AMoversChainIsKeptWhileTheFrontEndDoesNotReportIt) {
  // Paper A's world, seeds 1..10, each robot alone: a moving landmark's chain in the graph is not
  // dropped within ten steps of its last reading unless the map names the track static, also
  // while the front end, for a while, does not report the track as a mover.
  int checks = 0;
  for (int seed = 1; seed <= 10; ++seed) {
    const auto o =
        common::LoadScenario(Config("paper_two_robots.yaml"), {"seed=" + std::to_string(seed), "filter.type=smoother"});
    for (std::size_t robot = 0; robot < o.robots.size(); ++robot) {
      OnlineSmoother smoother(common::AgentOptionsFor(o, o.robots[robot].id), o.seed);
      const auto source = world_sim::MakeStepSource(o);
      std::map<std::uint32_t, int> last_read;
      std::vector<std::uint32_t> chains;  // tracks with a chain after the step before
      for (int k = 1; k <= o.run.steps; ++k) {
        smoother.Process(source->Step().at(robot));
        const filters::FilterEstimate e = smoother.Estimate();
        for (const std::uint32_t track : chains) {
          const bool named_static = std::any_of(e.landmarks.begin(), e.landmarks.end(), [&](const auto& l) {
            return l.track_id == track && l.motion == filters::LandmarkMotionKind::kStatic;
          });
          if (named_static || k - last_read[track] > 10) continue;
          EXPECT_GT(smoother.Graph().ChainStates(track), 0) << "seed " << seed << " robot " << robot << " step " << k;
          ++checks;
        }
        for (const std::uint32_t track : e.detection_tracks) {
          if (track != 0) last_read[track] = k;
        }
        chains.clear();
        for (const auto& m : smoother.Graph().Movers()) chains.push_back(m.track);
      }
    }
  }
  EXPECT_GT(checks, 50);
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
