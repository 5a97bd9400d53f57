// Hostile or broken peer input reaching an agent: rejected, counted, the map unchanged.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "robot_agent/cooperation/cooperation.h"
#include "tests/robot_agent/cooperation_sim.h"

namespace mrslam::robot_agent::cooperation {
namespace {

class HostileInput : public ::testing::Test {
 protected:
  HostileInput()
      : sim_(
            Scenario(3), [](std::uint32_t k, int i, int j) { return i == 0 && j == 1 && k >= 14 && k <= 15; }, 4) {
    sim_.Run(20);  // r1 knows r2's frame; r3 is a known robot whose frame r1 does not know
  }

  MapSnapshot GoodSnapshot() const {
    MapSnapshot m;
    m.header = {"r2", "r1", sim_.step(), 13.0, 1};
    filters::MapLandmark l;
    l.mean = {10.0, 10.0, 0.0};
    l.covariance = Eigen::Vector3d(0.01, 0.01, 1.0).asDiagonal();
    m.landmarks.push_back(l);
    return m;
  }
  RelativeMeasurement GoodMeasurement() const {
    RelativeMeasurement m;
    m.header = {"r2", "r1", sim_.step(), 13.0, 1};
    m.range_m = 2.0;
    m.bearing_rad = 0.5;
    m.sender_covariance = Eigen::Matrix3d::Identity() * 1e-3;
    return m;
  }
  // Applies the inbox; expects it rejected (one count per message, `stale` of them as only out of
  // order) with the map unchanged.
  void ExpectRejected(const PeerInbox& inbox, int stale = 0) {
    Cooperation& a = sim_.agent(0);
    const int before = a.rejected_messages();
    const int stale_before = a.stale_messages();
    const auto landmarks = sim_.filter(0).estimate.landmarks;
    const int merges = sim_.filter(0).merges;
    const auto frames = a.frames_known();
    a.Receive(inbox, &sim_.filter(0));
    EXPECT_EQ(a.rejected_messages(),
              before + static_cast<int>(inbox.measurements.size() + inbox.maps.size() + inbox.moved.size()));
    EXPECT_EQ(a.stale_messages(), stale_before + stale);
    EXPECT_EQ(sim_.filter(0).merges, merges);
    EXPECT_EQ(sim_.filter(0).estimate.landmarks.size(), landmarks.size());
    EXPECT_EQ(a.frames_known(), frames);
  }

  Sim sim_;
};

TEST_F(HostileInput, GoodSnapshotIsMerged) {
  ASSERT_EQ(sim_.agent(0).frames_known(), std::vector<std::string>{"r2"});
  const int merges = sim_.filter(0).merges;
  sim_.agent(0).Receive({{}, {GoodSnapshot()}, {}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges + 1);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 0);
}

TEST_F(HostileInput, MoversWithAnEstimatedMotionAreNotMerged) {
  // A moving landmark the peer tracks with a constant turn rate stays out of the own map; one
  // that follows known kinematics is merged.
  MapSnapshot estimated = GoodSnapshot();
  estimated.landmarks[0].moving = true;
  estimated.landmarks[0].motion = filters::LandmarkMotionKind::kConstantTurnRate;
  const int merges = sim_.filter(0).merges;
  sim_.agent(0).Receive({{}, {estimated}, {}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges);
  MapSnapshot known = GoodSnapshot();
  known.landmarks[0].moving = true;
  known.landmarks[0].motion = filters::LandmarkMotionKind::kUnicycle;
  sim_.agent(0).Receive({{}, {known}, {}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges + 1);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 0);
}

TEST_F(HostileInput, NanAndInfinity) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks[0].mean.x() = std::nan("");
  MapSnapshot b = GoodSnapshot();
  b.landmarks[0].covariance(1, 1) = std::numeric_limits<double>::infinity();
  MapSnapshot c = GoodSnapshot();
  c.landmarks[0].v_mps = std::nan("");
  RelativeMeasurement m = GoodMeasurement();
  m.range_m = std::nan("");
  RelativeMeasurement n = GoodMeasurement();
  n.sender_pose.heading = std::numeric_limits<double>::infinity();
  ExpectRejected({{m, n}, {a, b, c}, {}, {}});
}

TEST_F(HostileInput, CovarianceNotSymmetricPositiveDefinite) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks[0].covariance(0, 0) = -0.01;
  MapSnapshot b = GoodSnapshot();
  b.landmarks[0].covariance(0, 1) = 0.005;  // not symmetric
  MapSnapshot c = GoodSnapshot();
  c.known_transforms.push_back({"r3", 1, {1.0, 2.0, 0.3}, Eigen::Matrix3d::Zero()});
  RelativeMeasurement m = GoodMeasurement();
  m.sender_covariance(2, 2) = 0.0;
  ExpectRejected({{m}, {a, b, c}, {}, {}});
}

TEST_F(HostileInput, UnknownRobots) {
  MapSnapshot a = GoodSnapshot();
  a.header.sender = "r9";
  MapSnapshot b = GoodSnapshot();
  b.known_transforms.push_back({"r9", 1, {1.0, 2.0, 0.3}, Eigen::Matrix3d::Identity()});
  MapSnapshot c = GoodSnapshot();
  c.header.recipient = "r3";
  RelativeMeasurement m = GoodMeasurement();
  m.header.sender = "r1";  // itself
  LandmarkMovedNotice n;
  n.header = {"r7", "r1", sim_.step(), 0.0, 1};
  ExpectRejected({{m}, {a, b, c}, {n}, {}});
}

// Landmarks carry their provenance (the robot that first mapped them): one naming a robot the
// scenario does not have is hostile input; r1's own landmarks coming back from r2 (after r2
// merged them) are not merged again, neither as duplicates nor as confirmation.
TEST_F(HostileInput, ProvenanceOfAnUnknownRobot) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks[0].origin_robot = 3;  // robots 0..2
  MapSnapshot b = GoodSnapshot();
  b.landmarks[0].origin_robot = -2;
  ExpectRejected({{}, {a, b}, {}, {}});
}

TEST_F(HostileInput, OwnLandmarksComingBackAreNotMergedAgain) {
  MapSnapshot echo = GoodSnapshot();
  echo.landmarks[0].origin_robot = 0;  // r1's
  echo.landmarks[0].origin_track = 5;
  const int merges = sim_.filter(0).merges;
  const std::size_t mapped = sim_.filter(0).estimate.landmarks.size();
  sim_.agent(0).Receive({{}, {echo}, {}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges);
  EXPECT_EQ(sim_.filter(0).estimate.landmarks.size(), mapped);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 0);  // not hostile: simply nothing new

  MapSnapshot mixed = GoodSnapshot();
  mixed.header.step = echo.header.step;
  mixed.landmarks.push_back(echo.landmarks[0]);
  mixed.landmarks[0].origin_robot = 2;  // r3's, merged by r2 earlier
  mixed.landmarks[1].mean.x() = -10.0;  // r1's, elsewhere
  sim_.agent(0).Receive({{}, {mixed}, {}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.filter(0).merges, merges + 1);
  ASSERT_EQ(sim_.filter(0).estimate.landmarks.size(), mapped + 1);  // r3's only
  EXPECT_EQ(sim_.filter(0).estimate.landmarks.back().origin_robot, 2);
}

TEST_F(HostileInput, AbsurdSize) {
  MapSnapshot a = GoodSnapshot();
  a.landmarks.assign(257, a.landmarks[0]);
  ExpectRejected({{}, {a}, {}, {}});
}

TEST_F(HostileInput, BrokenHistories) {
  // A history of every step up to the snapshot's, with one labelled reading per step.
  const auto with_history = [this]() {
    MapSnapshot m = GoodSnapshot();
    for (std::uint32_t k = 1; k <= m.header.step; ++k) {
      common::SensorStep s;
      s.lidar.stamp = {"r2", k, 0.65 * k};
      s.lidar.landmarks.push_back({0.65 * k, 3.0, 0.2, 1});
      s.odometry.segments.push_back({0.65 * (k - 1), 0.65, 1.0, 0.2});
      m.history.push_back(s);
    }
    return m;
  };
  // The well-formed one is taken (its joint estimate may or may not be used: no shared landmark).
  sim_.agent(0).Receive({{}, {with_history()}, {}, {}}, &sim_.filter(0));
  ASSERT_EQ(sim_.agent(0).rejected_messages(), 0);
  MapSnapshot nan = with_history();
  nan.history[3].lidar.landmarks[0].range_m = std::nan("");
  MapSnapshot odometry = with_history();
  odometry.history[2].odometry.segments[0].v_mps = std::numeric_limits<double>::infinity();
  MapSnapshot gap = with_history();
  gap.history.erase(gap.history.begin() + 5);
  MapSnapshot unlabelled = with_history();
  unlabelled.history[0].lidar.landmarks[0].landmark_id = -1;
  MapSnapshot first_pose = with_history();
  first_pose.first_pose.x = std::nan("");
  MapSnapshot extra = with_history();  // more steps than the snapshot's
  extra.history.push_back(extra.history.back());
  MapSnapshot crowded = with_history();  // more readings in one step than any scan holds
  crowded.history[1].lidar.landmarks.assign(257, crowded.history[1].lidar.landmarks[0]);
  ExpectRejected({{}, {nan, odometry, gap, unlabelled, first_pose, extra, crowded}, {}, {}});
}

TEST_F(HostileInput, StaleAndFutureSteps) {
  sim_.agent(0).Receive({{}, {GoodSnapshot()}, {}, {}}, &sim_.filter(0));
  MapSnapshot a = GoodSnapshot();
  a.header.step = sim_.step() - 5;  // older than the one just applied
  MapSnapshot b = GoodSnapshot();
  b.header.step = sim_.step() + 100;
  RelativeMeasurement m = GoodMeasurement();
  m.header.step = 14;                        // r2's measurements up to step 15 were applied
  ExpectRejected({{m}, {a, b}, {}, {}}, 2);  // a and m only out of order; b from the future
}

TEST_F(HostileInput, SnapshotFromAPeerWhoseFrameIsUnknownIsHeldNotApplied) {
  MapSnapshot a = GoodSnapshot();
  a.header.sender = "r3";
  Cooperation& agent = sim_.agent(0);
  const int merges = sim_.filter(0).merges;
  agent.Receive({{}, {a}, {}, {}}, &sim_.filter(0));
  EXPECT_EQ(agent.rejected_messages(), 0);
  EXPECT_EQ(sim_.filter(0).merges, merges);
  EXPECT_EQ(agent.frames_known(), std::vector<std::string>{"r2"});
}

TEST_F(HostileInput, MovedNoticesAreValidatedAndCounted) {
  LandmarkMovedNotice good;
  good.header = {"r2", "r1", sim_.step(), 0.0, 1};
  good.position_in_sender = {1.0, 2.0};
  sim_.agent(0).Receive({{}, {}, {good}, {}}, &sim_.filter(0));
  EXPECT_EQ(sim_.agent(0).moved_notices(), 1);
  LandmarkMovedNotice bad = good;
  bad.position_in_sender.x() = std::nan("");
  ExpectRejected({{}, {}, {bad}, {}});
  EXPECT_EQ(sim_.agent(0).moved_notices(), 1);
  LandmarkMovedNotice unknown_frame = good;
  unknown_frame.header.sender = "r3";
  sim_.agent(0).Receive({{}, {}, {unknown_frame}, {}}, &sim_.filter(0));  // held until r3's frame is known
  EXPECT_EQ(sim_.agent(0).moved_notices(), 1);
  EXPECT_EQ(sim_.agent(0).rejected_messages(), 1);
}

// In realtime a peer's snapshot or notice can overtake the detections that make the rendezvous:
// it is held, and applied once the frame is known.
TEST(EarlyPeerMessages, AreAppliedOnceTheSendersFrameIsKnown) {
  const auto meet = [](std::uint32_t k, int i, int j) { return i == 0 && j == 1 && k >= 14 && k <= 15; };
  Sim early(Scenario(2), meet, 4);
  Sim alone(Scenario(2), meet, 4);
  early.Run(12);
  alone.Run(12);
  ASSERT_TRUE(early.agent(0).frames_known().empty());
  MapSnapshot snapshot;
  snapshot.header = {"r2", "r1", early.step(), 0.65 * early.step(), 1};
  filters::MapLandmark far;
  far.mean = {10.0, 10.0, 0.0};
  far.covariance = Eigen::Vector3d(0.01, 0.01, 1.0).asDiagonal();
  far.origin_robot = 1;  // r2's own
  snapshot.landmarks.push_back(far);
  LandmarkMovedNotice notice;
  notice.header = {"r2", "r1", early.step(), 0.65 * early.step(), 2};
  notice.position_in_sender = {1.0, 2.0};
  early.agent(0).Receive({{}, {snapshot}, {notice}, {}}, &early.filter(0));
  MapSnapshot older = snapshot;  // overtaken in turn: the newer one stays held
  older.header.step -= 1;
  older.landmarks[0].mean = {-10.0, -10.0, 0.0};
  early.agent(0).Receive({{}, {older}, {}, {}}, &early.filter(0));
  EXPECT_EQ(early.agent(0).rejected_messages(), 0);
  EXPECT_EQ(early.filter(0).merges, 0);
  EXPECT_TRUE(early.filter(0).notices.empty());

  early.Run(8);
  alone.Run(8);
  ASSERT_EQ(early.agent(0).frames_known(), std::vector<std::string>{"r2"});
  EXPECT_EQ(early.agent(0).rejected_messages(), 0);
  EXPECT_EQ(early.filter(0).merges, alone.filter(0).merges + 1);
  ASSERT_EQ(early.filter(0).notices.size(), 1U);
  const Eigen::Vector2d truth = common::TransformPoint(early.TrueTransform(0, 1), notice.position_in_sender);
  EXPECT_LT((early.filter(0).notices[0].first - truth).norm(), 0.3);
  const Eigen::Vector2d far_truth = common::TransformPoint(early.TrueTransform(0, 1), far.mean.head<2>());
  const auto& mapped = early.filter(0).estimate.landmarks;
  // Within 1 m: 14 m from r1, where a hundredth of a radian of the transform's heading is 0.14 m.
  EXPECT_TRUE(std::any_of(mapped.begin(), mapped.end(),
                          [&](const filters::MapLandmark& l) { return (l.mean.head<2>() - far_truth).norm() < 1.0; }));
  const Eigen::Vector2d older_truth =
      common::TransformPoint(early.TrueTransform(0, 1), older.landmarks[0].mean.head<2>());
  EXPECT_TRUE(std::none_of(mapped.begin(), mapped.end(), [&](const filters::MapLandmark& l) {
    return (l.mean.head<2>() - older_truth).norm() < 1.0;
  }));
}

TEST_F(HostileInput, MovedNoticeReachesTheFilterInTheOwnFrame) {
  const std::optional<FrameTransform> t12 = Find(sim_.agent(0).known_transforms(), "r2");
  ASSERT_TRUE(t12.has_value());
  LandmarkMovedNotice n;
  n.header = {"r2", "r1", sim_.step(), 0.0, 1};
  n.position_in_sender = {1.0, 2.0};
  sim_.filter(0).notices.clear();
  sim_.agent(0).Receive({{}, {}, {n}, {}}, &sim_.filter(0));
  ASSERT_EQ(sim_.filter(0).notices.size(), 1U);
  const Eigen::Vector2d expected = common::TransformPoint(t12->t_self_peer, n.position_in_sender);
  EXPECT_NEAR((sim_.filter(0).notices[0].first - expected).norm(), 0.0, 1e-12);
  // The transform's uncertainty reaches the notice: a positive definite position covariance.
  EXPECT_TRUE(common::IsSymmetricPositiveDefinite<2>(sim_.filter(0).notices[0].second));
}

TEST_F(HostileInput, MovedNoticesGoOnlyToPeersWhoseFrameIsKnown) {
  filters::MovedLandmark m;
  m.track_id = 4;
  m.position = {3.0, -1.0};
  const auto notices = sim_.agent(0).MovedNotices({m}, sim_.step(), 13.0);
  ASSERT_EQ(notices.size(), 1U);  // r2 (met); not r3 (frame unknown)
  EXPECT_EQ(notices[0].header.recipient, "r2");
  EXPECT_EQ(notices[0].header.sender, "r1");
  EXPECT_EQ(notices[0].track_id, 4U);
  EXPECT_EQ(notices[0].position_in_sender, m.position);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
