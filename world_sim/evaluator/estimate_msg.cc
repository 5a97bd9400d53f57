#include "world_sim/evaluator/estimate_msg.h"

#include "common/dds/msg_conversion.h"

namespace mrslam::evaluator {

namespace {

MapLandmark ToMapLandmark(const msg::LandmarkEstimate& l) {
  MapLandmark m;
  m.position_m = Eigen::Vector2d(l.pose().x_m(), l.pose().y_m());
  const auto& c = l.covariance();  // row-major 3x3 over (x, y, heading)
  m.covariance_m2 << c[0], c[1], c[3], c[4];
  m.landmark_id = l.landmark_id();
  m.moving = l.moving();
  m.heading_rad = l.pose().heading_rad();
  m.v_mps = l.v_mps();
  return m;
}

}  // namespace

RobotEstimate FromEstimateMsg(const msg::Estimate& m) {
  RobotEstimate e;
  e.step = m.stamp().step();
  e.time_s = m.stamp().time_s();
  e.pose = dds::FromMsg(m.pose());
  e.covariance = dds::CovarianceFromMsg(m.covariance());
  e.effective_sample_size = m.effective_sample_size();
  for (const auto& l : m.landmarks()) {
    if (l.tentative()) continue;
    e.shown_landmarks.push_back(ToMapLandmark(l));
    e.landmarks.push_back({e.shown_landmarks.back().position_m, l.landmark_id(), e.shown_landmarks.back().covariance_m2,
                           l.origin_robot()});
  }
  e.frames_known = m.frames_known();
  for (const auto& h : m.data_held()) e.data_held[h.robot_id()] = h.steps();
  e.rejected_samples = m.rejected_samples();
  e.step_cpu_ms = m.step_cpu_ms();
  e.peer_bytes_sent = m.peer_bytes_sent();
  e.peer_bytes_received = m.peer_bytes_received();
  e.peer_messages_late = m.peer_messages_late();
  e.data_hop_us = m.data_hop_us();
  e.estimator_bytes = m.estimator_bytes();
  e.final_trajectory_chunks = m.final_trajectory_chunks();
  for (const auto& r : m.rendezvous()) e.rendezvous.push_back({r.peer_id(), r.step(), dds::FromMsg(r.t_self_peer())});
  return e;
}

}  // namespace mrslam::evaluator
