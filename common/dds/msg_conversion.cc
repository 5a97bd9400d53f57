#include "common/dds/msg_conversion.h"

#include <vector>

namespace mrslam::dds {

msg::Stamp ToMsg(const common::Stamp& s) {
  msg::Stamp m;
  m.robot_id(s.robot_id);
  m.step(s.step);
  m.time_s(s.time_s);
  return m;
}
common::Stamp FromMsg(const msg::Stamp& s) { return {s.robot_id(), s.step(), s.time_s()}; }

msg::Pose2D ToMsg(const common::Pose2& p) {
  msg::Pose2D m;
  m.x_m(p.x);
  m.y_m(p.y);
  m.heading_rad(p.heading);
  return m;
}
common::Pose2 FromMsg(const msg::Pose2D& p) { return {p.x_m(), p.y_m(), p.heading_rad()}; }

std::array<double, 9> CovarianceToMsg(const Eigen::Matrix3d& m) {
  std::array<double, 9> a{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a[3 * static_cast<std::size_t>(r) + static_cast<std::size_t>(c)] = m(r, c);
  }
  return a;
}

Eigen::Matrix3d CovarianceFromMsg(const std::array<double, 9>& a) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = a[3 * static_cast<std::size_t>(r) + static_cast<std::size_t>(c)];
  }
  return m;
}

namespace {
msg::LandmarkDetection ItemToMsg(const common::LandmarkDetection& d) {
  msg::LandmarkDetection m;
  m.time_s(d.time_s);
  m.range_m(d.range_m);
  m.bearing_rad(d.bearing_rad);
  m.landmark_id(d.landmark_id);
  return m;
}
msg::RobotDetection ItemToMsg(const common::RobotDetection& d) {
  msg::RobotDetection m;
  m.time_s(d.time_s);
  m.range_m(d.range_m);
  m.bearing_rad(d.bearing_rad);
  m.seen_robot_id(d.seen_robot_id);
  return m;
}
msg::ImuReading ItemToMsg(const common::ImuReading& r) {
  msg::ImuReading m;
  m.time_s(r.time_s);
  m.gyro_z_radps(r.gyro_z_radps);
  m.accel_x_mps2(r.accel_x_mps2);
  m.accel_y_mps2(r.accel_y_mps2);
  return m;
}
msg::OdometrySegment ItemToMsg(const common::OdometrySegment& g) {
  msg::OdometrySegment m;
  m.time_s(g.time_s);
  m.dt_s(g.dt_s);
  m.v_mps(g.v_mps);
  m.w_radps(g.w_radps);
  return m;
}
common::LandmarkDetection ItemFromMsg(const msg::LandmarkDetection& d) {
  return {d.time_s(), d.range_m(), d.bearing_rad(), d.landmark_id()};
}
common::RobotDetection ItemFromMsg(const msg::RobotDetection& d) {
  return {d.time_s(), d.range_m(), d.bearing_rad(), d.seen_robot_id()};
}
common::ImuReading ItemFromMsg(const msg::ImuReading& r) {
  return {r.time_s(), r.gyro_z_radps(), r.accel_x_mps2(), r.accel_y_mps2()};
}
common::OdometrySegment ItemFromMsg(const msg::OdometrySegment& g) {
  return {g.time_s(), g.dt_s(), g.v_mps(), g.w_radps()};
}

// Every item of a sequence converted, in order.
template <typename Out, typename In>
std::vector<Out> ItemsToMsg(const std::vector<In>& items) {
  std::vector<Out> out;
  out.reserve(items.size());
  for (const auto& item : items) out.push_back(ItemToMsg(item));
  return out;
}
template <typename Out, typename In>
std::vector<Out> ItemsFromMsg(const std::vector<In>& items) {
  std::vector<Out> out;
  out.reserve(items.size());
  for (const auto& item : items) out.push_back(ItemFromMsg(item));
  return out;
}
}  // namespace

msg::LidarScan ToMsg(const common::LidarScan& scan) {
  msg::LidarScan m;
  m.stamp(ToMsg(scan.stamp));
  m.landmarks(ItemsToMsg<msg::LandmarkDetection>(scan.landmarks));
  m.robots(ItemsToMsg<msg::RobotDetection>(scan.robots));
  return m;
}

common::LidarScan FromMsg(const msg::LidarScan& scan) {
  return {FromMsg(scan.stamp()), ItemsFromMsg<common::LandmarkDetection>(scan.landmarks()),
          ItemsFromMsg<common::RobotDetection>(scan.robots())};
}

msg::Odometry ToMsg(const common::Odometry& odom) {
  msg::Odometry m;
  m.stamp(ToMsg(odom.stamp));
  m.segments(ItemsToMsg<msg::OdometrySegment>(odom.segments));
  return m;
}

common::Odometry FromMsg(const msg::Odometry& odom) {
  return {FromMsg(odom.stamp()), ItemsFromMsg<common::OdometrySegment>(odom.segments())};
}

msg::SensorStep ToMsg(const common::SensorStep& step) {
  msg::SensorStep m;
  m.stamp(ToMsg(step.odometry.stamp));
  m.landmarks(ItemsToMsg<msg::LandmarkDetection>(step.lidar.landmarks));
  m.robots(ItemsToMsg<msg::RobotDetection>(step.lidar.robots));
  m.imu_readings(ItemsToMsg<msg::ImuReading>(step.imu.readings));
  m.odometry_segments(ItemsToMsg<msg::OdometrySegment>(step.odometry.segments));
  return m;
}

common::SensorStep FromMsg(const msg::SensorStep& step) {
  const common::Stamp stamp = FromMsg(step.stamp());
  return {{stamp, ItemsFromMsg<common::LandmarkDetection>(step.landmarks()),
           ItemsFromMsg<common::RobotDetection>(step.robots())},
          {stamp, ItemsFromMsg<common::ImuReading>(step.imu_readings())},
          {stamp, ItemsFromMsg<common::OdometrySegment>(step.odometry_segments())}};
}

namespace {
msg::EntityTruth EntityToMsg(const common::EntityTruth& e) {
  msg::EntityTruth m;
  m.entity_id(e.id);
  m.pose(ToMsg(e.pose));
  m.moving(e.moving);
  return m;
}
common::EntityTruth EntityFromMsg(const msg::EntityTruth& e) { return {e.entity_id(), FromMsg(e.pose()), e.moving()}; }
}  // namespace

msg::GroundTruth ToMsg(const common::GroundTruth& truth) {
  msg::GroundTruth m;
  m.stamp(ToMsg(truth.stamp));
  for (const auto& r : truth.robots) m.robots().push_back(EntityToMsg(r));
  for (const auto& l : truth.landmarks) m.landmarks().push_back(EntityToMsg(l));
  for (const auto& [id, frame] : truth.frames) {
    msg::RobotFrameTruth f;
    f.robot_id(id);
    f.frame_in_world(ToMsg(frame));
    m.frames().push_back(f);
  }
  return m;
}

common::GroundTruth FromMsg(const msg::GroundTruth& truth) {
  common::GroundTruth t;
  t.stamp = FromMsg(truth.stamp());
  for (const auto& r : truth.robots()) t.robots.push_back(EntityFromMsg(r));
  for (const auto& l : truth.landmarks()) t.landmarks.push_back(EntityFromMsg(l));
  for (const auto& f : truth.frames()) t.frames.emplace_back(f.robot_id(), FromMsg(f.frame_in_world()));
  return t;
}

}  // namespace mrslam::dds
