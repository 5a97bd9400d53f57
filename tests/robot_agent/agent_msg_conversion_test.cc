// Round trips of the agent's estimate and peer messages through their DDS types.
#include "robot_agent/node/msg_conversion.h"

#include <gtest/gtest.h>

#include "robot_agent/cooperation/factor_exchange.h"

namespace mrslam::robot_agent {
namespace {

filters::MapLandmark SomeLandmark(int k) {
  filters::MapLandmark l;
  l.track_id = 10U + static_cast<std::uint32_t>(k);
  l.landmark_id = k - 1;
  l.mean = {1.0 * k, -2.0, 0.3};
  l.covariance = Eigen::Matrix3d::Identity() * (0.1 + k);
  l.covariance(0, 1) = l.covariance(1, 0) = 0.01;
  l.v_mps = 0.4;
  l.w_radps = 0.2;
  l.motion = filters::LandmarkMotionKind::kUnicycle;
  l.moving = true;
  l.tentative = k % 2 == 0;
  l.last_seen_step = 42;
  l.origin_robot = k % 3 - 1;
  l.origin_track = 70U + static_cast<std::uint32_t>(k);
  return l;
}

void ExpectSame(const filters::MapLandmark& a, const filters::MapLandmark& b) {
  EXPECT_EQ(a.track_id, b.track_id);
  EXPECT_EQ(a.landmark_id, b.landmark_id);
  EXPECT_EQ(a.mean, b.mean);
  EXPECT_EQ(a.covariance, b.covariance);
  EXPECT_EQ(a.v_mps, b.v_mps);
  EXPECT_EQ(a.w_radps, b.w_radps);
  EXPECT_EQ(a.motion, b.motion);
  EXPECT_EQ(a.moving, b.moving);
  EXPECT_EQ(a.tentative, b.tentative);
  EXPECT_EQ(a.last_seen_step, b.last_seen_step);
  EXPECT_EQ(a.origin_robot, b.origin_robot);
  EXPECT_EQ(a.origin_track, b.origin_track);
}

TEST(AgentMsgConversionTest, EstimateRoundTrip) {
  filters::FilterEstimate e;
  e.step = 9;
  e.time_s = 5.85;
  e.pose = {1.0, 2.0, -0.4};
  e.covariance = Eigen::Matrix3d::Identity() * 0.02;
  e.effective_sample_size = 512.5;
  e.particles = 1000;
  e.landmarks = {SomeLandmark(1), SomeLandmark(2)};
  const auto m = ToMsg(e, "r2", "fastslam");
  EXPECT_EQ(m.stamp().robot_id(), "r2");
  EXPECT_EQ(m.filter(), "fastslam");
  const auto back = FromMsg(m);
  EXPECT_EQ(back.step, e.step);
  EXPECT_EQ(back.time_s, e.time_s);
  EXPECT_EQ(back.pose.heading, e.pose.heading);
  EXPECT_EQ(back.covariance, e.covariance);
  EXPECT_EQ(back.effective_sample_size, e.effective_sample_size);
  EXPECT_EQ(back.particles, e.particles);
  ASSERT_EQ(back.landmarks.size(), 2U);
  for (std::size_t i = 0; i < 2; ++i) ExpectSame(back.landmarks[i], e.landmarks[i]);
}

TEST(AgentMsgConversionTest, PeerMessagesRoundTrip) {
  cooperation::RelativeMeasurement r;
  r.header = {"r1", "r2", 14, 9.1, 3};
  r.range_m = 4.2;
  r.bearing_rad = -1.1;
  r.sender_pose = {0.5, 0.6, 0.7};
  r.sender_covariance = Eigen::Matrix3d::Identity() * 0.3;
  const auto rb = FromMsg(ToMsg(r));
  EXPECT_EQ(rb.header.sender, "r1");
  EXPECT_EQ(rb.header.recipient, "r2");
  EXPECT_EQ(rb.header.step, 14U);
  EXPECT_EQ(rb.header.sequence, 3U);
  EXPECT_EQ(rb.range_m, r.range_m);
  EXPECT_EQ(rb.bearing_rad, r.bearing_rad);
  EXPECT_EQ(rb.sender_pose.y, r.sender_pose.y);
  EXPECT_EQ(rb.sender_covariance, r.sender_covariance);

  cooperation::MapSnapshot s;
  s.header = {"r3", "r1", 20, 13.0, 1};
  s.landmarks = {SomeLandmark(3)};
  s.known_transforms.push_back({"r4", 18, {1.0, -2.0, 0.6}, Eigen::Matrix3d::Identity() * 0.05});
  const auto sb = FromMsg(ToMsg(s));
  EXPECT_EQ(sb.header.sender, "r3");
  ASSERT_EQ(sb.landmarks.size(), 1U);
  ExpectSame(sb.landmarks[0], s.landmarks[0]);
  ASSERT_EQ(sb.known_transforms.size(), 1U);
  EXPECT_EQ(sb.known_transforms[0].peer, "r4");
  EXPECT_EQ(sb.known_transforms[0].t_self_peer.heading, 0.6);
  EXPECT_EQ(sb.known_transforms[0].covariance, s.known_transforms[0].covariance);
  EXPECT_TRUE(sb.history.empty());

  // A snapshot with a history: its first pose and every step's odometry and scan.
  cooperation::MapSnapshot h = s;
  h.first_pose = {-0.2, -0.5, 1.23};
  for (std::uint32_t k = 1; k <= 3; ++k) {
    common::SensorStep step;
    step.lidar.stamp = {"r3", k, 0.65 * k};
    step.lidar.landmarks.push_back({0.65 * k, 2.5 + k, -0.3, static_cast<int>(k)});
    step.lidar.robots.push_back({0.65 * k, 4.0, 0.1, "r1"});
    step.odometry.stamp = step.lidar.stamp;
    step.odometry.segments.push_back({0.65 * (k - 1), 0.65, 1.0, 0.2});
    h.history.push_back(step);
  }
  const auto hb = FromMsg(ToMsg(h));
  EXPECT_EQ(hb.first_pose.Vector(), h.first_pose.Vector());
  ASSERT_EQ(hb.history.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(hb.history[i].lidar.stamp.step, i + 1);
    ASSERT_EQ(hb.history[i].lidar.landmarks.size(), 1U);
    EXPECT_EQ(hb.history[i].lidar.landmarks[0].landmark_id, static_cast<int>(i + 1));
    EXPECT_EQ(hb.history[i].lidar.landmarks[0].range_m, h.history[i].lidar.landmarks[0].range_m);
    ASSERT_EQ(hb.history[i].lidar.robots.size(), 1U);
    EXPECT_EQ(hb.history[i].lidar.robots[0].seen_robot_id, "r1");
    ASSERT_EQ(hb.history[i].odometry.segments.size(), 1U);
    EXPECT_EQ(hb.history[i].odometry.segments[0].w_radps, 0.2);
  }

  cooperation::LandmarkMovedNotice n;
  n.header = {"r2", "r1", 30, 19.5, 7};
  n.track_id = 5;
  n.landmark_id = 12;
  n.position_in_sender = {3.5, -0.25};
  const auto nb = FromMsg(ToMsg(n));
  EXPECT_EQ(nb.track_id, 5U);
  EXPECT_EQ(nb.landmark_id, 12);
  EXPECT_EQ(nb.position_in_sender, n.position_in_sender);
  EXPECT_EQ(nb.header.sequence, 7U);
}

template <typename D>
void ExpectSameReading(const D& x, const D& y) {
  EXPECT_EQ(x.time_s, y.time_s);
  EXPECT_EQ(x.range_m, y.range_m);
  EXPECT_EQ(x.bearing_rad, y.bearing_rad);
}

void ExpectBitEqual(const common::SensorStep& a, const common::SensorStep& b) {
  EXPECT_EQ(a.lidar.stamp.robot_id, b.lidar.stamp.robot_id);
  EXPECT_EQ(a.lidar.stamp.step, b.lidar.stamp.step);
  EXPECT_EQ(a.lidar.stamp.time_s, b.lidar.stamp.time_s);
  EXPECT_EQ(a.odometry.stamp.time_s, b.odometry.stamp.time_s);
  ASSERT_EQ(a.odometry.segments.size(), b.odometry.segments.size());
  for (std::size_t i = 0; i < a.odometry.segments.size(); ++i) {
    const auto &x = a.odometry.segments[i], &y = b.odometry.segments[i];
    EXPECT_EQ(x.time_s, y.time_s);
    EXPECT_EQ(x.dt_s, y.dt_s);
    EXPECT_EQ(x.v_mps, y.v_mps);
    EXPECT_EQ(x.w_radps, y.w_radps);
  }
  ASSERT_EQ(a.lidar.landmarks.size(), b.lidar.landmarks.size());
  for (std::size_t i = 0; i < a.lidar.landmarks.size(); ++i) {
    ExpectSameReading(a.lidar.landmarks[i], b.lidar.landmarks[i]);
    EXPECT_EQ(a.lidar.landmarks[i].landmark_id, b.lidar.landmarks[i].landmark_id);
  }
  ASSERT_EQ(a.lidar.robots.size(), b.lidar.robots.size());
  for (std::size_t i = 0; i < a.lidar.robots.size(); ++i) {
    ExpectSameReading(a.lidar.robots[i], b.lidar.robots[i]);
    EXPECT_EQ(a.lidar.robots[i].seen_robot_id, b.lidar.robots[i].seen_robot_id);
  }
}

TEST(AgentMsgConversionTest, SharedStepsArriveAsTheOriginHoldsThem) {
  // Steps with times late in a long run, irregular offsets and values that single precision
  // rounds: in their shared form (the origin's own log) they travel to the bit, in a run and as
  // the opening step.
  cooperation::FactorBatch b;
  b.header = {"r3", "r1", 9001, 900.1, 4};
  b.opened_by_step = 9001;
  cooperation::FactorRun run{"r3", 8999, {0.1, -0.2, 0.3}, {}, {}};
  for (std::uint32_t k = 8999; k <= 9001; ++k) {
    common::SensorStep step;
    const double t = 0.1 * k + 1e-9 * k;
    step.lidar.stamp = {"r3", k, t};
    step.odometry.stamp = {"r3", k, t - 0.05};  // not the scan's: the shared form has one stamp
    step.odometry.segments.push_back({t - 0.2 - 1.0 / 3e4, 0.0151234567, 0.312345678901, -0.0998765432101});
    step.odometry.segments.push_back({t - 0.1849, 0.0848765, 0.3 + 1e-12, 0.1 / 3.0});
    step.lidar.landmarks.push_back({t + 1.0 / 7e3, 2.123456789012, -0.3 / 7.0, 12});
    step.lidar.robots.push_back({t - 1e-3 / 3.0, 4.0 / 3.0, 0.1 / 9.0, "r1"});
    const common::SensorStep shared = cooperation::SharedPrecision(step);
    ExpectBitEqual(cooperation::SharedPrecision(shared), shared);
    EXPECT_NE(shared.odometry.segments[0].v_mps, step.odometry.segments[0].v_mps);  // rounded
    EXPECT_NEAR(shared.odometry.segments[0].v_mps, step.odometry.segments[0].v_mps, 1e-7);
    EXPECT_NEAR(shared.odometry.segments[0].time_s, step.odometry.segments[0].time_s, 5e-7);
    run.steps.push_back(shared);
  }
  b.runs.push_back(run);
  b.opening.push_back(run.steps.back());
  const auto back = FromMsg(ToMsg(b));
  ASSERT_EQ(back.runs.size(), 1U);
  EXPECT_EQ(back.runs[0].origin, "r3");
  EXPECT_EQ(back.runs[0].first_step, 8999U);
  ASSERT_EQ(back.runs[0].steps.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) ExpectBitEqual(back.runs[0].steps[i], run.steps[i]);
  ASSERT_EQ(back.opening.size(), 1U);
  ExpectBitEqual(back.opening[0], run.steps.back());
}

TEST(AgentMsgConversionTest, TrackEstimatesAndHoldingsArriveAsSent) {
  cooperation::TrackEstimate t;
  t.label = 12;
  t.step = 9000;
  t.mean = {12.345678901, -3.0 / 7.0, 2.9};
  t.position_covariance << 0.0123456789, -0.001 / 3.0, -0.001 / 3.0, 0.02;
  t.heading_var = 0.3 / 7.0;
  t.v_mps = 0.2 / 3.0;
  t.w_radps = -0.01 / 3.0;
  t.moving = true;
  const cooperation::TrackEstimate shared = cooperation::SharedPrecision(t);
  EXPECT_NE(shared.mean.x(), t.mean.x());  // rounded
  EXPECT_NEAR(shared.mean.x(), t.mean.x(), 1e-5);
  cooperation::FactorBatch b;
  b.header = {"r3", "r1", 9001, 900.1, 4};
  b.opened_by_step = 9001;
  b.runs.push_back({"r3", 8999, {}, {common::SensorStep{}, common::SensorStep{}}, {shared}});
  b.holdings = {{"r3", 9001, "", 0}, {"r2", 4000, "r4", 8990}};
  b.heard = {{"r2", 8995, {{"r2", 8995, "", 0}, {"r3", 7000, "r1", 8000}}}};
  const auto back = FromMsg(ToMsg(b));
  ASSERT_EQ(back.holdings.size(), 2U);
  EXPECT_EQ(back.holdings[1].origin, "r2");
  EXPECT_EQ(back.holdings[1].steps, 4000U);
  EXPECT_EQ(back.holdings[1].fed_by, "r4");
  EXPECT_EQ(back.holdings[1].fed_at, 8990U);
  ASSERT_EQ(back.heard.size(), 1U);
  EXPECT_EQ(back.heard[0].robot, "r2");
  EXPECT_EQ(back.heard[0].step, 8995U);
  ASSERT_EQ(back.heard[0].holdings.size(), 2U);
  EXPECT_EQ(back.heard[0].holdings[1].origin, "r3");
  EXPECT_EQ(back.heard[0].holdings[1].steps, 7000U);
  EXPECT_EQ(back.heard[0].holdings[1].fed_by, "r1");
  EXPECT_EQ(back.heard[0].holdings[1].fed_at, 8000U);
  ASSERT_EQ(back.runs.size(), 1U);
  ASSERT_EQ(back.runs[0].tracks.size(), 1U);
  const cooperation::TrackEstimate& r = back.runs[0].tracks[0];
  EXPECT_EQ(r.label, 12U);
  EXPECT_EQ(r.step, 9000U);
  EXPECT_EQ(r.mean, shared.mean);
  EXPECT_EQ(r.position_covariance, shared.position_covariance);
  EXPECT_EQ(r.heading_var, shared.heading_var);
  EXPECT_EQ(r.v_mps, shared.v_mps);
  EXPECT_EQ(r.w_radps, shared.w_radps);
  EXPECT_TRUE(r.moving);
}

}  // namespace
}  // namespace mrslam::robot_agent
