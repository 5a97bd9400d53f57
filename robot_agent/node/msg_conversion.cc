#include "robot_agent/node/msg_conversion.h"

#include "common/dds/msg_conversion.h"

namespace mrslam::robot_agent {

namespace {
std::array<double, 9> ToArray(const Eigen::Matrix3d& m) {
  std::array<double, 9> a{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a[static_cast<std::size_t>(3 * r + c)] = m(r, c);
  }
  return a;
}
Eigen::Matrix3d FromArray(const std::array<double, 9>& a) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = a[static_cast<std::size_t>(3 * r + c)];
  }
  return m;
}
}  // namespace

msg::Estimate ToMsg(const FilterEstimate& e, const std::string& robot_id, const std::string& filter) {
  msg::Estimate m;
  m.stamp(dds::ToMsg(common::Stamp{robot_id, e.step, e.time_s}));
  m.filter(filter);
  m.pose(dds::ToMsg(e.pose));
  m.covariance(ToArray(e.covariance));
  m.effective_sample_size(e.effective_sample_size);
  m.particles(static_cast<std::uint32_t>(e.particles));
  for (const auto& l : e.landmarks) {
    msg::LandmarkEstimate ml;
    ml.track_id(l.track_id);
    ml.landmark_id(l.landmark_id);
    ml.pose(dds::ToMsg(common::Pose2{l.mean.x(), l.mean.y(), l.mean.z()}));
    ml.covariance(ToArray(l.covariance));
    ml.v_mps(l.v_mps);
    ml.w_radps(l.w_radps);
    ml.motion_model(static_cast<std::uint8_t>(l.motion));
    ml.moving(l.moving);
    ml.tentative(l.tentative);
    ml.last_seen_step(l.last_seen_step);
    m.landmarks().push_back(ml);
  }
  return m;
}

FilterEstimate FromMsg(const msg::Estimate& m) {
  FilterEstimate e;
  e.step = m.stamp().step();
  e.time_s = m.stamp().time_s();
  e.pose = dds::FromMsg(m.pose());
  e.covariance = FromArray(m.covariance());
  e.effective_sample_size = m.effective_sample_size();
  e.particles = static_cast<int>(m.particles());
  for (const auto& ml : m.landmarks()) {
    MapLandmark l;
    l.track_id = ml.track_id();
    l.landmark_id = ml.landmark_id();
    const auto p = dds::FromMsg(ml.pose());
    l.mean = {p.x, p.y, p.heading};
    l.covariance = FromArray(ml.covariance());
    l.v_mps = ml.v_mps();
    l.w_radps = ml.w_radps();
    l.motion = static_cast<LandmarkMotionKind>(ml.motion_model());
    l.moving = ml.moving();
    l.tentative = ml.tentative();
    l.last_seen_step = ml.last_seen_step();
    e.landmarks.push_back(l);
  }
  return e;
}

}  // namespace mrslam::robot_agent
