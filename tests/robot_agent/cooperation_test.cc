// The agents' protocol in process: rendezvous, snapshots and merges, frames that chain through
// peers, cooperative localization (agents with fake filters, tests/robot_agent/cooperation_sim.h).
#include "robot_agent/cooperation/cooperation.h"

#include <cstdint>
#include <optional>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/robot_agent/cooperation_sim.h"
#include "tests/test_matchers.h"

namespace mrslam::robot_agent::cooperation {
namespace {

using mrslam::testing::IsNearlyPose;

// ---------------------------------------------------------------------------------------------
// Cooperation among agents, in process, with a fake filter.

TEST(Cooperation, TwoAgentsMeetAgreeAndMergeMaps) {
  // In sight of each other from step 5 to 30 (the detector acts from step 14).
  Sim sim(
      Scenario(2), [](std::uint32_t k, int, int) { return k >= 5 && k <= 30; }, 21);
  sim.Run(14);
  EXPECT_TRUE(sim.agent(0).rendezvous().empty());  // step 14's messages arrive at 15
  sim.Run(1);
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 1u);
  ASSERT_EQ(sim.agent(1).rendezvous().size(), 1u);
  EXPECT_EQ(sim.agent(0).rendezvous()[0].peer, "r2");
  EXPECT_EQ(sim.agent(1).rendezvous()[0].peer, "r1");
  EXPECT_EQ(sim.agent(0).rendezvous()[0].step, 14u);
  EXPECT_EQ(sim.agent(1).rendezvous()[0].step, 14u);
  EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  EXPECT_EQ(sim.sent_maps, 2);  // one snapshot each way, in AfterStep of step 15
  EXPECT_EQ(sim.filter(0).merges, 0);
  sim.Run(1);
  EXPECT_EQ(sim.filter(0).merges, 1);
  EXPECT_EQ(sim.filter(1).merges, 1);
  // Each knew 2 landmarks, one shared: the merged maps hold 3, in the right place.
  for (std::size_t i = 0; i < 2; ++i) {
    ASSERT_EQ(sim.filter(i).estimate.landmarks.size(), 3u) << "robot " << i;
    for (const auto& l : sim.filter(i).estimate.landmarks) {
      double best = std::numeric_limits<double>::infinity();
      for (const auto& truth : sim.landmarks()) {
        const Eigen::Vector2d in_own = common::TransformPoint(common::Inverse(sim.Frame(i)), truth);
        best = std::min(best, (in_own - l.mean.head<2>()).norm());
      }
      EXPECT_LT(best, 0.3);
    }
  }
  sim.Run(30);
  // One continuous contact: one rendezvous, refined; later contact steps change nothing else.
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 1u);
  EXPECT_EQ(sim.sent_maps, 2);
  const RendezvousEvent& e01 = sim.agent(0).rendezvous()[0];
  const RendezvousEvent& e10 = sim.agent(1).rendezvous()[0];
  EXPECT_THAT(common::Compose(e01.t_self_peer, e10.t_self_peer), IsNearlyPose(Pose2{}, 0.01, 0.01));
  EXPECT_LT(Nees(e01.t_self_peer, sim.TrueTransform(0, 1), e01.covariance), 16.3);  // chi2(3) 0.999
  const std::optional<FrameTransform> t01 = Find(sim.agent(0).known_transforms(), "r2");
  const std::optional<FrameTransform> t10 = Find(sim.agent(1).known_transforms(), "r1");
  ASSERT_TRUE(t01.has_value());
  ASSERT_TRUE(t10.has_value());
  EXPECT_THAT(common::Compose(t01->t_self_peer, t10->t_self_peer), IsNearlyPose(Pose2{}, 0.01, 0.01));
  EXPECT_LT(Nees(t01->t_self_peer, sim.TrueTransform(0, 1), t01->covariance), 16.3);
  EXPECT_EQ(sim.agent(0).rejected_messages(), 0);
  EXPECT_EQ(sim.agent(1).rejected_messages(), 0);
}

// A landmark of the own map goes into snapshots once it has been seen over
// cooperation.min_seen_span_steps (6) steps; one a peer passed on goes as it came.
TEST(Cooperation, OwnLandmarksAreSharedOnceSeenLongEnough) {
  // r1's first landmark is its own alone; r2 holds the second and third. Seen from step
  // `first` to step 12, by r1 itself or (origin 2) by r3, which r1 met earlier.
  const auto r2_landmarks_after_merge = [](std::uint32_t first, int origin) {
    Sim sim(
        Scenario(3), [](std::uint32_t k, int i, int j) { return i == 0 && j == 1 && k >= 5 && k <= 30; }, 21);
    filters::MapLandmark& l = sim.filter(0).estimate.landmarks[0];
    l.origin_robot = origin;
    l.origin_track = l.track_id;
    l.first_seen_step = first;
    l.last_seen_step = 12;
    sim.Run(16);
    EXPECT_EQ(sim.filter(1).merges, 1);
    return sim.filter(1).estimate.landmarks.size();
  };
  EXPECT_EQ(r2_landmarks_after_merge(7, 0), 2u);  // seen over 5 steps: withheld
  EXPECT_EQ(r2_landmarks_after_merge(6, 0), 3u);  // over 6: shared and added
  EXPECT_EQ(r2_landmarks_after_merge(7, 2), 3u);  // r3's: passed on
}

// The refined transform stays consistent over seeds and is more precise than one detection.
TEST(Cooperation, RefinedTransformIsConsistentOverSeeds) {
  double nees_sum = 0.0;
  constexpr int kSeeds = 200;
  for (int seed = 0; seed < kSeeds; ++seed) {
    Sim sim(
        Scenario(2), [](std::uint32_t k, int, int) { return k >= 14 && k <= 24; }, 100 + seed);
    sim.Run(26);
    const RendezvousEvent& e = sim.agent(0).rendezvous().at(0);
    nees_sum += Nees(e.t_self_peer, sim.TrueTransform(0, 1), e.covariance);
  }
  EXPECT_LT(nees_sum / kSeeds, 3.0 * 1.2);
}

TEST(Cooperation, RendezvousRepeatsOnlyAfterTheMinimumInterval) {
  // Contacts at 14-16, 25-26 (too soon: refines, no event), 40-41 (a second rendezvous).
  Sim sim(
      Scenario(2),
      [](std::uint32_t k, int, int) { return (k >= 14 && k <= 16) || (k >= 25 && k <= 26) || (k >= 40 && k <= 41); },
      5);
  sim.Run(50);
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 2u);
  EXPECT_EQ(sim.agent(0).rendezvous()[1].step, 40u);
  EXPECT_EQ(sim.agent(1).rendezvous()[1].step, 40u);
  EXPECT_EQ(sim.sent_maps, 4);
  EXPECT_EQ(sim.filter(0).merges, 2);
}

// A snapshot is merged only while the sender's mutual detections agree with the transform held
// to its frame: here r2 is 1.5 m and 0.3 rad off in its own frame at the second rendezvous (its
// covariance does not say so), the detections fall outside the transform gate, and neither
// robot merges the other's map there; the frames stay known.
TEST(Cooperation, NoMergeWhileTheSendersDetectionsDisagreeWithTheTransform) {
  for (const bool lost : {false, true}) {
    Sim sim(
        Scenario(2), [](std::uint32_t k, int, int) { return (k >= 14 && k <= 16) || (k >= 40 && k <= 41); }, 5);
    sim.Run(30);
    EXPECT_EQ(sim.filter(0).merges, 1);
    if (lost) sim.SetPoseError(1, {1.5, 0.0, 0.3});
    sim.Run(20);
    ASSERT_EQ(sim.agent(0).rendezvous().size(), 2u);
    EXPECT_EQ(sim.sent_maps, 4);
    EXPECT_EQ(sim.filter(0).merges, lost ? 1 : 2) << "lost " << lost;
    EXPECT_EQ(sim.filter(1).merges, lost ? 1 : 2) << "lost " << lost;
    EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  }
}

TEST(Cooperation, NothingBeforeTheDetectorIsEnabled) {
  Sim sim(
      Scenario(2), [](std::uint32_t k, int, int) { return k < 14; }, 5);
  sim.Run(20);
  EXPECT_TRUE(sim.agent(0).rendezvous().empty());
  EXPECT_TRUE(sim.agent(0).frames_known().empty());
}

TEST(Cooperation, FramesChainThroughPeers) {
  // r1-r2 meet at 14; r2-r3 at 20; r1-r2 again at 40 (r2's snapshot carries T(G2 <- G3)).
  Sim sim(
      Scenario(3),
      [](std::uint32_t k, int i, int j) {
        if (i == 0 && j == 1) return (k >= 14 && k <= 15) || (k >= 40 && k <= 41);
        if (i == 1 && j == 2) return k >= 20 && k <= 21;
        return false;
      },
      9);
  sim.Run(30);
  EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  // r3 learnt r1's frame from r2's snapshot at their rendezvous, never meeting r1.
  EXPECT_EQ(sim.agent(2).frames_known(), (std::vector<std::string>{"r1", "r2"}));
  sim.Run(20);
  EXPECT_EQ(sim.agent(0).frames_known(), (std::vector<std::string>{"r2", "r3"}));
  const std::optional<FrameTransform> t13 = Find(sim.agent(0).known_transforms(), "r3");
  ASSERT_TRUE(t13.has_value());
  EXPECT_LT(Nees(t13->t_self_peer, sim.TrueTransform(0, 2), t13->covariance), 16.3);
  const std::optional<FrameTransform> t31 = Find(sim.agent(2).known_transforms(), "r1");
  ASSERT_TRUE(t31.has_value());
  EXPECT_LT(Nees(t31->t_self_peer, sim.TrueTransform(2, 0), t31->covariance), 16.3);
  // Maps spread: r1 holds r3's landmark (index 3) after the second meeting with r2.
  const Eigen::Vector2d l3 = common::TransformPoint(common::Inverse(sim.Frame(0)), sim.landmarks()[3]);
  bool found = false;
  for (const auto& l : sim.filter(0).estimate.landmarks) found = found || (l.mean.head<2>() - l3).norm() < 0.3;
  EXPECT_TRUE(found);
}

TEST(Cooperation, FramesSpreadDuringALongEncounter) {
  // r1 and r2 stay in contact from step 14 on (one encounter, one rendezvous); r2 meets r3 at
  // 30. Every 10 steps of the encounter r2 passes its transforms on, without its map.
  Sim sim(
      Scenario(3),
      [](std::uint32_t k, int i, int j) {
        if (i == 0 && j == 1) return k >= 14;
        if (i == 1 && j == 2) return k >= 30 && k <= 31;
        return false;
      },
      11);
  sim.Run(30);
  EXPECT_EQ(sim.agent(0).frames_known(), std::vector<std::string>{"r2"});
  sim.Run(15);
  ASSERT_EQ(sim.agent(0).rendezvous().size(), 1u);
  EXPECT_EQ(sim.agent(0).frames_known(), (std::vector<std::string>{"r2", "r3"}));
  const std::optional<FrameTransform> t13 = Find(sim.agent(0).known_transforms(), "r3");
  ASSERT_TRUE(t13.has_value());
  EXPECT_LT(Nees(t13->t_self_peer, sim.TrueTransform(0, 2), t13->covariance), 16.3);
  EXPECT_EQ(sim.filter(0).merges, 1);  // the rendezvous' snapshot only
}

TEST(Cooperation, CooperativeLocalizationUsesDetectionsAfterTheRefinement) {
  common::ScenarioOptions s = Scenario(2);
  s.cooperation.cooperative_localization = true;
  Sim sim(
      s, [](std::uint32_t k, int, int) { return k >= 14 && k <= 40; }, 3);
  sim.Run(45);
  // Steps 14..24 refine the transform; 25..40 correct the pose (applied at the next step).
  EXPECT_EQ(sim.filter(0).robot_observations, 16);
  EXPECT_EQ(sim.agent(0).cooperative_updates(), 16);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
