// Multi-process: world_sim and three robot_agent processes on tests/integration/data/
// three_robots.yaml. r2 and r3 meet at once, r1 and r2 half a lap later: rendezvous fire on
// both sides of each pair with transforms that are each other's inverse and close to the truth,
// r1 places r3 by chaining through r2, and r1's map holds landmarks it never came within lidar
// range of, placed where they truly are (in r1's frame).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "common/angles.h"
#include "common/config/scenario_options.h"
#include "common/dds/msg_conversion.h"
#include "common/se2.h"
#include "tests/integration/run_recorder.h"

namespace mrslam {
namespace {

using testing::SourcePath;

constexpr int kDomain = 118;  // this test's own DDS domain

// The first rendezvous of `self` with `peer` in the last estimate, or nullptr.
const msg::RendezvousEvent* FirstRendezvous(const msg::Estimate& e, const std::string& peer) {
  for (const auto& r : e.rendezvous()) {
    if (r.peer_id() == peer) return &r;
  }
  return nullptr;
}

bool Knows(const msg::Estimate& e, const std::string& peer) {
  return std::find(e.frames_known().begin(), e.frames_known().end(), peer) != e.frames_known().end();
}

TEST(ThreeAgentsMergeTest, RendezvousFireFramesChainAndPeerLandmarksEnterTheMap) {
  unsetenv("MRSLAM_DOMAIN");
  const std::string scenario_path = SourcePath("tests/integration/data/three_robots.yaml");
  const auto scenario = common::LoadScenario(scenario_path, {});
  const testing::TempDir temp_dir("mrslam-three");
  const std::string& dir = temp_dir.path();
  const std::vector<std::string> args = {"--scenario", scenario_path, "--domain", std::to_string(kDomain)};
  testing::RunRecorder recorder(kDomain, scenario);
  recorder.Run(args, dir);
  if (HasFatalFailure()) return;

  std::map<std::string, msg::Estimate> last;
  for (const auto& r : scenario.robots) {
    const auto& list = recorder.estimates(r.id);
    ASSERT_EQ(list.size(), static_cast<std::size_t>(scenario.run.steps)) << r.id;
    last[r.id] = list.back();
  }

  // Rendezvous on both sides of the pairs that meet; none between r1 and r3, who never do.
  for (const auto& [a, b] : std::vector<std::pair<std::string, std::string>>{{"r2", "r3"}, {"r1", "r2"}}) {
    const msg::RendezvousEvent* ab = FirstRendezvous(last[a], b);
    const msg::RendezvousEvent* ba = FirstRendezvous(last[b], a);
    ASSERT_NE(ab, nullptr) << a << " has no rendezvous with " << b;
    ASSERT_NE(ba, nullptr) << b << " has no rendezvous with " << a;
    EXPECT_EQ(ab->step(), ba->step()) << a << "-" << b;
    // Both sides compute the transform from the same mutual measurements and exchanged pose
    // estimates: T(G_a <- G_b) T(G_b <- G_a) is the identity up to what each side adds on its own
    // (2 cm and 0.2 degrees here: ten times below the transforms' own errors, 0.04-0.4 m and
    // about 1 degree).
    const common::Pose2 loop = common::Compose(dds::FromMsg(ab->t_self_peer()), dds::FromMsg(ba->t_self_peer()));
    EXPECT_LT(std::hypot(loop.x, loop.y), 0.02) << a << "-" << b;
    EXPECT_LT(common::DegFromRad(std::abs(loop.heading)), 0.2) << a << "-" << b;
    // Against the truth: the robots' drift by the encounter (odometry 0.02 m/s and 0.01 rad/s
    // noise, at most half a lap) stays well under 1 m and 5 degrees here.
    const common::Pose2 truth = common::Between(recorder.Frame(a), recorder.Frame(b));
    const common::Pose2 error = common::Between(truth, dds::FromMsg(ab->t_self_peer()));
    EXPECT_LT(std::hypot(error.x, error.y), 1.0) << a << "-" << b;
    EXPECT_LT(common::DegFromRad(std::abs(error.heading)), 5.0) << a << "-" << b;
    std::cout << a << "-" << b << " at step " << ab->step() << ": transform error " << std::hypot(error.x, error.y)
              << " m, " << common::DegFromRad(std::abs(error.heading)) << " deg\n";
  }
  EXPECT_EQ(FirstRendezvous(last["r1"], "r3"), nullptr);
  // Every robot ends knowing every other robot's frame: r1 and r3 by chaining through r2.
  for (const auto& [self, peers] : std::map<std::string, std::vector<std::string>>{
           {"r1", {"r2", "r3"}}, {"r2", {"r1", "r3"}}, {"r3", {"r1", "r2"}}}) {
    for (const auto& peer : peers) EXPECT_TRUE(Knows(last[self], peer)) << self << " does not know " << peer;
  }

  // The landmarks r1 could have seen itself: those within lidar range of its true path.
  const double range = scenario.sensors.lidar.max_range_m;
  const auto& truth_first = recorder.truth().begin()->second;
  std::set<std::string> seen_by_r1;
  for (const auto& [step, truth] : recorder.truth()) {
    const common::Pose2 r1 = recorder.TruePose(step, "r1");
    for (const auto& l : truth.landmarks) {
      if (std::hypot(l.pose.x - r1.x, l.pose.y - r1.y) <= range) seen_by_r1.insert(l.id);
    }
  }
  // r1's final map in the world frame: every landmark is within 1 m of a true one (merging put
  // nothing where there is nothing), and some of them r1 never had in range: they came from
  // its peers, through the transforms.
  const common::Pose2 frame = recorder.Frame("r1");
  int from_peers = 0;
  for (const auto& l : last["r1"].landmarks()) {
    const Eigen::Vector2d p = common::TransformPoint(frame, {l.pose().x_m(), l.pose().y_m()});
    double best = 1e9;
    std::string best_id;
    for (const auto& t : truth_first.landmarks) {
      const double d = std::hypot(t.pose.x - p.x(), t.pose.y - p.y());
      if (d < best) {
        best = d;
        best_id = t.id;
      }
    }
    EXPECT_LT(best, 1.0) << "r1's landmark " << l.track_id() << " is " << best << " m from any true landmark";
    if (seen_by_r1.count(best_id) == 0) ++from_peers;
  }
  std::cout << "r1: " << last["r1"].landmarks().size() << " landmarks, " << from_peers
            << " of them never in its own lidar range\n";
  EXPECT_GE(from_peers, 5);
}

}  // namespace
}  // namespace mrslam
