#include "common/dds/msg_conversion.h"

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

msg::LidarScan ToMsg(const common::LidarScan& scan) {
  msg::LidarScan m;
  m.stamp(ToMsg(scan.stamp));
  for (const auto& d : scan.landmarks) {
    msg::LandmarkDetection md;
    md.time_s(d.time_s);
    md.range_m(d.range_m);
    md.bearing_rad(d.bearing_rad);
    md.landmark_id(d.landmark_id);
    m.landmarks().push_back(md);
  }
  for (const auto& d : scan.robots) {
    msg::RobotDetection md;
    md.time_s(d.time_s);
    md.range_m(d.range_m);
    md.bearing_rad(d.bearing_rad);
    md.seen_robot_id(d.seen_robot_id);
    m.robots().push_back(md);
  }
  return m;
}

common::LidarScan FromMsg(const msg::LidarScan& scan) {
  common::LidarScan s;
  s.stamp = FromMsg(scan.stamp());
  for (const auto& d : scan.landmarks()) {
    s.landmarks.push_back({d.time_s(), d.range_m(), d.bearing_rad(), d.landmark_id()});
  }
  for (const auto& d : scan.robots()) {
    s.robots.push_back({d.time_s(), d.range_m(), d.bearing_rad(), d.seen_robot_id()});
  }
  return s;
}

msg::Imu ToMsg(const common::ImuSamples& imu) {
  msg::Imu m;
  m.stamp(ToMsg(imu.stamp));
  for (const auto& r : imu.readings) {
    msg::ImuReading mr;
    mr.time_s(r.time_s);
    mr.gyro_z_radps(r.gyro_z_radps);
    mr.accel_x_mps2(r.accel_x_mps2);
    mr.accel_y_mps2(r.accel_y_mps2);
    m.readings().push_back(mr);
  }
  return m;
}

common::ImuSamples FromMsg(const msg::Imu& imu) {
  common::ImuSamples s;
  s.stamp = FromMsg(imu.stamp());
  for (const auto& r : imu.readings()) {
    s.readings.push_back({r.time_s(), r.gyro_z_radps(), r.accel_x_mps2(), r.accel_y_mps2()});
  }
  return s;
}

msg::Odometry ToMsg(const common::Odometry& odom) {
  msg::Odometry m;
  m.stamp(ToMsg(odom.stamp));
  for (const auto& g : odom.segments) {
    msg::OdometrySegment mg;
    mg.time_s(g.time_s);
    mg.dt_s(g.dt_s);
    mg.v_mps(g.v_mps);
    mg.w_radps(g.w_radps);
    m.segments().push_back(mg);
  }
  return m;
}

common::Odometry FromMsg(const msg::Odometry& odom) {
  common::Odometry s;
  s.stamp = FromMsg(odom.stamp());
  for (const auto& g : odom.segments()) s.segments.push_back({g.time_s(), g.dt_s(), g.v_mps(), g.w_radps()});
  return s;
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
