#include "robot_agent/cooperation/joint_chains.h"

#include <cmath>
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
#include "robot_agent/cooperation/joint_tracker.h"
#include "robot_agent/cooperation/rendezvous.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::robot_agent::cooperation {
namespace {

const std::string kPaperScenario = std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/paper_two_robots.yaml";

// paper_two_robots with reported identities, each robot's track of a landmark labelled by its
// identity (so the right correspondence is known), for `steps` steps.
struct PaperRun {
  common::ScenarioOptions scenario;
  AgentOptions r1;
  std::map<std::string, FactorLog> logs;  // whole
  std::vector<common::Pose2> truth_r1;    // per step 1..n, in G1
  common::Pose2 t_r1_r2;                  // T(G1 <- G2)
};

PaperRun RecordPaper(int seed, int steps) {
  PaperRun run;
  run.scenario = common::LoadScenario(
      kPaperScenario,
      {"seed=" + std::to_string(seed), "sensors.lidar.report_identity=true", "run.steps=" + std::to_string(steps)});
  run.r1 = common::AgentOptionsFor(run.scenario, "r1");
  run.r1.cooperation.share_factors = true;
  run.r1.filter.type = "smoother";
  // The agent labels its shared readings by its tracks (here: the identities the simulation
  // reports, so that the right correspondence is known).
  run.r1.sensors.lidar.report_identity = false;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(run.scenario);
  const auto frames = source->Truth().frames;
  run.t_r1_r2 = common::Between(frames[0].second, frames[1].second);
  for (int r = 0; r < 2; ++r) {
    run.logs[run.scenario.robots[r].id].first_pose = common::InitialPoseInOwnFrame(run.scenario.robots[r]);
  }
  for (int k = 0; k < steps; ++k) {
    const std::vector<common::SensorStep> step = source->Step();
    for (int r = 0; r < 2; ++r) run.logs[run.scenario.robots[r].id].steps.push_back(step[r]);
    run.truth_r1.push_back(common::Compose(common::Inverse(frames[0].second), source->Truth().robots[0].pose));
  }
  return run;
}

// r1's map as its filter would report it: each landmark a track (its identity) following its
// known candidate.
filters::FilterEstimate OwnMap(const PaperRun& run) {
  filters::FilterEstimate e;
  for (const auto& l : run.scenario.landmarks) {
    filters::MapLandmark m;
    m.track_id = static_cast<std::uint32_t>(l.id);
    m.motion = filters::LandmarkMotionKind::kUnicycle;
    m.v_mps = l.motion.v_mps;
    m.w_radps = l.motion.w_radps;
    m.covariance = 0.1 * Eigen::Matrix3d::Identity();
    e.landmarks.push_back(m);
  }
  return e;
}

// r2's tracks as r1 knows them from a snapshot: each matched to r1's track `match[its track]`.
PeerTrackLinks Links(const PaperRun& run, const std::map<int, std::uint32_t>& match) {
  PeerTrackLinks links;
  for (const auto& l : OwnMap(run).landmarks) {
    const int track = static_cast<int>(l.track_id);
    links["r2"][track] = {match.at(track), *TrackKinematics(run.r1.filter, l)};
  }
  return links;
}

// The logs as held after step k.
std::map<std::string, FactorLog> HeldAt(const PaperRun& run, int k) {
  std::map<std::string, FactorLog> held = run.logs;
  for (auto& [id, log] : held) log.steps.resize(static_cast<std::size_t>(k));
  return held;
}

// r2's frame as r1 holds it: the true one.
std::vector<FrameTransform> TrueFrame(const PaperRun& run) {
  return {{"r2", 0, run.t_r1_r2, 0.01 * Eigen::Matrix3d::Identity()}};
}

// The oracle's joint estimate of both robots (true identities and kinematics), r2's first pose
// started at the truth.
smoother::BatchSmoother JointOracle(const PaperRun& run) {
  const common::Pose2 guess = common::Compose(run.t_r1_r2, run.logs.at("r2").first_pose);
  return batch::OracleSmoother(run.scenario, {0, 1}, {guess}, run.scenario.rendezvous.enable_from_step);
}

TEST(JointChains, KeepsTheCandidateATrackWasSeenToFollow) {
  const std::optional<int> seen = 1, never;
  EXPECT_EQ(KeptKinematics(seen, kStaticKinematics), 1);  // a mover taken as static for a while
  EXPECT_EQ(KeptKinematics(seen, std::nullopt), 1);
  EXPECT_EQ(KeptKinematics(seen, 0), 0);  // seen to follow another candidate now
  EXPECT_EQ(KeptKinematics(never, kStaticKinematics), kStaticKinematics);
  EXPECT_EQ(KeptKinematics(never, std::nullopt), std::nullopt);
}

TEST(JointChains, IsTheJointEstimateOfBothRobotsData) {
  // Every step of both robots held, r2's tracks matched to r1's: r1's pose at every step is the
  // oracle's joint estimate of the same data (both solve the same problem, from other starts).
  const int steps = 60;
  const PaperRun run = RecordPaper(3, steps);
  JointChains chains(run.r1);
  const std::vector<FrameTransform> frames = TrueFrame(run);
  const PeerTrackLinks links = Links(run, {{1, 1}, {2, 2}});
  smoother::BatchSmoother oracle = JointOracle(run);
  double joint = 0.0, oracle_error = 0.0;
  for (int k = 1; k <= steps; ++k) {
    oracle.Process({run.logs.at("r1").steps[k - 1], run.logs.at("r2").steps[k - 1]});
    const auto own = chains.Update(static_cast<std::uint32_t>(k), OwnMap(run), HeldAt(run, k), links, frames);
    ASSERT_TRUE(own.has_value()) << "step " << k;
    EXPECT_LT((own->pose.Translation() - oracle.Pose().Translation()).norm(), 0.01) << "step " << k;
    EXPECT_LT(std::abs(common::WrapAngle(own->pose.heading - oracle.Pose().heading)), 0.005) << "step " << k;
    joint += (own->pose.Translation() - run.truth_r1[k - 1].Translation()).squaredNorm();
    oracle_error += (oracle.Pose().Translation() - run.truth_r1[k - 1].Translation()).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(joint / steps), std::sqrt(oracle_error / steps), 0.005);
  // The peer's frame from the solution, within a few sd of the truth.
  const JointEstimate summary = chains.Summary();
  ASSERT_EQ(summary.frames.size(), 1U);
  EXPECT_EQ(summary.path.size(), static_cast<std::size_t>(steps + 1));
  const common::Pose2& t = summary.frames[0].t_self_robot;
  const Eigen::Vector3d d(t.x - run.t_r1_r2.x, t.y - run.t_r1_r2.y, common::WrapAngle(t.heading - run.t_r1_r2.heading));
  EXPECT_LT(d.dot(summary.frames[0].covariance.ldlt().solve(d)), ChiSquare3Quantile(0.999)) << d.transpose();
}

TEST(JointChains, WithIdentitiesEveryRobotsLabelsNameTheSameLandmarks) {
  // The sensor reports identities: every robot's shared readings are labelled identity + 1 and
  // no snapshot is needed to join them; the own tracks are numbered otherwise.
  const int steps = 40;
  const PaperRun original = RecordPaper(3, steps);
  PaperRun run = original;
  run.r1.sensors.lidar.report_identity = true;
  for (auto& [id, log] : run.logs) {
    for (auto& step : log.steps) {
      for (auto& d : step.lidar.landmarks) d.landmark_id += 1;
    }
  }
  filters::FilterEstimate own = OwnMap(run);
  for (auto& l : own.landmarks) {
    l.landmark_id = static_cast<int>(l.track_id);
    l.track_id += 100;
  }
  JointChains chains(run.r1);
  smoother::BatchSmoother oracle = JointOracle(run);
  std::optional<JointChains::OwnPose> joint;
  for (int k = 1; k <= steps; ++k) {
    oracle.Process({original.logs.at("r1").steps[k - 1], original.logs.at("r2").steps[k - 1]});
    joint = chains.Update(static_cast<std::uint32_t>(k), own, HeldAt(run, k), {}, TrueFrame(run));
    ASSERT_TRUE(joint.has_value()) << "step " << k;
  }
  EXPECT_LT((joint->pose.Translation() - oracle.Pose().Translation()).norm(), 0.01);
  EXPECT_EQ(chains.Summary().frames.size(), 1U);
}

TEST(JointChains, LearnsACorrespondenceNoSnapshotMade) {
  // r2's track of landmark 2 was matched to none of r1's: the joint solution puts it on r1's
  // track 2, so from the next step on it is r1's landmark 2.
  const PaperRun run = RecordPaper(3, 40);
  JointChains chains(run.r1);
  const std::vector<FrameTransform> frames = TrueFrame(run);
  const PeerTrackLinks links = Links(run, {{1, 1}, {2, 0}});
  smoother::BatchSmoother oracle = JointOracle(run);
  std::optional<JointChains::OwnPose> own;
  for (int k = 1; k <= 40; ++k) {
    oracle.Process({run.logs.at("r1").steps[k - 1], run.logs.at("r2").steps[k - 1]});
    own = chains.Update(static_cast<std::uint32_t>(k), OwnMap(run), HeldAt(run, k), links, frames);
  }
  ASSERT_TRUE(own.has_value());
  EXPECT_LT((own->pose.Translation() - oracle.Pose().Translation()).norm(), 0.01);
}

TEST(JointChains, BuiltColdLateIsTheSameEstimate) {
  // A tracker that starts at step 60 with everything held (as after a restore, or a peer whose
  // data come late) solves as the problem grows and reaches the estimate of one that followed
  // every step.
  const int steps = 60;
  const PaperRun run = RecordPaper(7, steps);
  const PeerTrackLinks links = Links(run, {{1, 1}, {2, 2}});
  JointChains followed(run.r1), late(run.r1);
  std::optional<JointChains::OwnPose> a;
  for (int k = 1; k <= steps; ++k) {
    a = followed.Update(static_cast<std::uint32_t>(k), OwnMap(run), HeldAt(run, k), links, TrueFrame(run));
  }
  const auto b = late.Update(steps, OwnMap(run), HeldAt(run, steps), links, TrueFrame(run));
  ASSERT_TRUE(a.has_value());
  ASSERT_TRUE(b.has_value());
  EXPECT_LT((a->pose.Translation() - b->pose.Translation()).norm(), 0.01);
  EXPECT_LT(std::abs(common::WrapAngle(a->pose.heading - b->pose.heading)), 0.005);
}

TEST(JointTracker, AmongMoversAWrongCorrespondenceMovesTheEstimateNoFurtherThanItsUncertainty) {
  // r1's "filter" reports the true pose with sd 0.1 m / 0.05 rad. With r2's tracks matched the
  // right way the tracker moves the estimate onto the joint one; with them swapped (each on the
  // landmark of the other candidate) the joint estimate is wrong, and the tracker keeps the
  // estimate within the filter's own uncertainty.
  const int steps = 60;
  const PaperRun run = RecordPaper(5, steps);
  const std::vector<FrameTransform> frames = TrueFrame(run);
  const double gate = ChiSquare3Quantile(run.r1.cooperation.transform_gate_probability);
  int moved_right = 0;
  double worst_wrong = 0.0;
  for (const bool swapped : {false, true}) {
    JointTracker tracker(run.r1);
    ASSERT_TRUE(JointTracker::Enabled(run.r1));
    const PeerTrackLinks links = Links(
        run, swapped ? std::map<int, std::uint32_t>{{1, 2}, {2, 1}} : std::map<int, std::uint32_t>{{1, 1}, {2, 2}});
    for (int k = 1; k <= steps; ++k) {
      filters::FilterEstimate estimate = OwnMap(run);
      estimate.step = static_cast<std::uint32_t>(k);
      estimate.pose = run.truth_r1[k - 1];
      estimate.covariance = Eigen::Vector3d(0.01, 0.01, 0.0025).asDiagonal();
      tracker.AfterStep(static_cast<std::uint32_t>(k), estimate, HeldAt(run, k),
                        std::uint64_t{2} * static_cast<std::uint64_t>(k), links, frames);
      const common::Pose2 p = tracker.Corrected(estimate).pose;
      const Eigen::Vector3d d(p.x - estimate.pose.x, p.y - estimate.pose.y,
                              common::WrapAngle(p.heading - estimate.pose.heading));
      const double d2 = d.dot(estimate.covariance.ldlt().solve(d));
      if (swapped) worst_wrong = std::max(worst_wrong, d2);
      if (!swapped && d.head<2>().norm() > 1e-3) ++moved_right;
    }
    EXPECT_EQ(tracker.solves(), steps);
  }
  EXPECT_GT(moved_right, steps / 2);
  EXPECT_LE(worst_wrong, gate);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
