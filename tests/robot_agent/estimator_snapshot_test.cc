// Every estimator's state survives a trip through an Archive: a filter restored from what another
// wrote after step k goes on exactly as the writer does (bit for bit), for FastSLAM's three
// landmark models, EKF-SLAM, ELA and the online smoother; a truncated or altered state is an
// ArchiveError, never a crash.
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/archive.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "robot_agent/factory/filter_factory.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::robot_agent {
namespace {

std::string Config(const std::string& name) { return std::string(MRSLAM_TEST_SOURCE_DIR) + "/config/" + name; }

std::unique_ptr<filters::SlamFilter> Make(const common::ScenarioOptions& o) {
  return factory::CreateFilter(common::AgentOptionsFor(o, o.robots.at(0).id), o.seed);
}

std::string Save(filters::SlamFilter* filter) {
  common::Archive ar = common::Archive::ForWriting();
  filter->Io(ar);
  return ar.bytes();
}

void ExpectSameEstimate(const filters::FilterEstimate& a, const filters::FilterEstimate& b, int step) {
  SCOPED_TRACE("step " + std::to_string(step));
  ASSERT_EQ(a.step, b.step);
  EXPECT_EQ(a.pose.x, b.pose.x);
  EXPECT_EQ(a.pose.y, b.pose.y);
  EXPECT_EQ(a.pose.heading, b.pose.heading);
  EXPECT_EQ(a.covariance, b.covariance);
  EXPECT_EQ(a.detection_tracks, b.detection_tracks);
  ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
  for (std::size_t i = 0; i < a.landmarks.size(); ++i) {
    EXPECT_EQ(a.landmarks[i].track_id, b.landmarks[i].track_id);
    EXPECT_EQ(a.landmarks[i].mean, b.landmarks[i].mean);
    EXPECT_EQ(a.landmarks[i].covariance, b.landmarks[i].covariance);
  }
}

// Runs r1 of the scenario for `split` steps, restores a second estimator from the first's state,
// then runs both to the end and compares every estimate after the split.
void ExpectRestoredGoesOnAlike(const std::string& config, const std::vector<std::string>& overrides, int split) {
  const auto o = common::LoadScenario(Config(config), overrides);
  ASSERT_LT(split, o.run.steps);
  const auto source = world_sim::MakeStepSource(o);
  auto original = Make(o);
  for (int k = 1; k <= split; ++k) original->Process(source->Step().at(0));
  auto restored = Make(o);
  common::Archive in = common::Archive::ForReading(Save(original.get()));
  restored->Io(in);
  EXPECT_TRUE(in.AtEnd());
  ExpectSameEstimate(original->Estimate(), restored->Estimate(), split);
  for (int k = split + 1; k <= o.run.steps; ++k) {
    const common::SensorStep step = source->Step().at(0);
    original->Process(step);
    restored->Process(step);
    ExpectSameEstimate(original->Estimate(), restored->Estimate(), k);
  }
  const auto a = original->FinalTrajectory();
  const auto b = restored->FinalTrajectory();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].first, b[i].first);
    EXPECT_EQ(a[i].second.Vector(), b[i].second.Vector());
  }
}

TEST(EstimatorSnapshot, FastSlamStaticLandmarks) {
  ExpectRestoredGoesOnAlike("paper_two_robots.yaml",
                            {"filter.landmark_kinematics=static", "filter.motion_source=imu", "filter.particles=50"},
                            40);
}

TEST(EstimatorSnapshot, FastSlamKnownCandidates) {
  ExpectRestoredGoesOnAlike("paper_two_robots.yaml", {"filter.particles=50"}, 40);
}

TEST(EstimatorSnapshot, FastSlamConstantTurnRate) {
  ExpectRestoredGoesOnAlike("swarm_8.yaml", {"filter.type=fastslam", "filter.particles=30", "run.steps=80"}, 50);
}

TEST(EstimatorSnapshot, EkfSlam) { ExpectRestoredGoesOnAlike("swarm_8.yaml", {"filter.type=ekf", "run.steps=80"}, 45); }

TEST(EstimatorSnapshot, EkfWithExpectedLandmarkAreas) {
  ExpectRestoredGoesOnAlike("swarm_8.yaml", {"filter.type=ekf_ela", "run.steps=80"}, 45);
}

TEST(EstimatorSnapshot, OnlineSmoother) {
  ExpectRestoredGoesOnAlike("swarm_8.yaml", {"filter.type=smoother", "run.steps=80"}, 47);
}

TEST(EstimatorSnapshot, ACutOrAlteredStateIsAnErrorNotACrash) {
  const auto o =
      common::LoadScenario(Config("swarm_8.yaml"), {"filter.type=fastslam", "filter.particles=20", "run.steps=30"});
  const auto source = world_sim::MakeStepSource(o);
  auto filter = Make(o);
  for (int k = 0; k < o.run.steps; ++k) filter->Process(source->Step().at(0));
  const std::string bytes = Save(filter.get());
  for (const std::size_t keep : {std::size_t{0}, std::size_t{7}, bytes.size() / 3, bytes.size() - 1}) {
    auto target = Make(o);
    common::Archive in = common::Archive::ForReading(bytes.substr(0, keep));
    EXPECT_THROW(target->Io(in), common::ArchiveError) << "kept " << keep << " of " << bytes.size() << " bytes";
  }
}

}  // namespace
}  // namespace mrslam::robot_agent
