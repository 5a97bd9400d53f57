#include "robot_agent/filters/ekf_slam.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/gaussian.h"
#include "robot_agent/filters/ela.h"
#include "robot_agent/filters/map_fusion.h"

namespace mrslam::robot_agent::filters {
namespace {

using common::kPi;
using common::WrapAngle;

// Variance of an angle about which nothing is known (uniform on a circle): pi^2 / 3. Reported as
// the heading variance of a static point landmark.
// A ghost (expected, unmatched mapped landmark) may be explained by motion over at most this
// many frames since it was last seen.
constexpr int kMaxGhostMotionFrames = 2;
// Unflagged observations counted before the first, so that an early false alarm or two (the
// drift and velocity tests flag about 1 - ela_gate_probability of a static world's observations)
// do not make the landmarks look creeping.
constexpr std::int64_t kCreepSharePriorObservations = 200;

// Symmetrizes a square matrix in place: P = (P + P^T) / 2.
void Symmetrize(Eigen::MatrixXd* p) {
  const int n = static_cast<int>(p->rows());
  for (int c = 0; c < n; ++c) {
    for (int r = c + 1; r < n; ++r) {
      const double v = 0.5 * ((*p)(r, c) + (*p)(c, r));
      (*p)(r, c) = v;
      (*p)(c, r) = v;
    }
  }
}

// The Joseph form for a measurement on rows j, j+1 of the state with H P = hp (2 x n), any gain K:
//   A = (I - K H) P = P - K (H P),  P = A (I - K H)^T + K R K^T = A - (A H^T) K^T + K R K^T,
// where A H^T is given by ah(A) (the caller's sparse H). Then symmetrized.
template <typename AhFn>
void JosephCovariance(Eigen::MatrixXd* p, const Eigen::MatrixXd& k, const Eigen::MatrixXd& hp, const Eigen::Matrix2d& r,
                      AhFn ah) {
  p->noalias() -= k * hp;
  const Eigen::MatrixXd a_ht = ah(*p);
  p->noalias() -= a_ht * k.transpose();
  p->noalias() += k * r * k.transpose();
  Symmetrize(p);
}

}  // namespace

EkfSlam::EkfSlam(const AgentOptions& options, bool ela)
    : filter_(options.filter),
      lidar_(options.sensors.lidar),
      odometry_(options.sensors.odometry),
      noise_(options.noise),
      step_dt_s_(options.dt_s),
      ela_(ela),
      gates_(AssociationGates::FromOptions(options.filter)),
      ela_gate_d2_(common::ChiSquare2Quantile(options.filter.ela_gate_probability)),
      robot_index_(options.TeamIndex(options.robot_id)) {
  r_ << lidar_.range_noise_sd_m * lidar_.range_noise_sd_m, 0.0, 0.0,
      lidar_.bearing_noise_sd_rad * lidar_.bearing_noise_sd_rad;
  x_ = options.initial_pose.Vector();
  p_ = Eigen::MatrixXd::Zero(3, 3);  // the initial pose in the own frame is known
}

Eigen::Vector2d EkfSlam::Measure(const Eigen::Vector3d& robot, const Eigen::Vector2d& m) {
  const double dx = m.x() - robot.x(), dy = m.y() - robot.y();
  return {std::hypot(dx, dy), WrapAngle(std::atan2(dy, dx) - robot.z())};
}

// With d = m - p_R, q = |d|^2, r = sqrt(q):
//   dr/dp_R = -d^T / r,  dr/dphi = 0,  dr/dm = d^T / r,
//   db/dp_R = (d_y, -d_x) / q,  db/dphi = -1,  db/dm = (-d_y, d_x) / q.
void EkfSlam::MeasureJacobians(const Eigen::Vector3d& robot, const Eigen::Vector2d& m, Eigen::Matrix<double, 2, 3>* h_r,
                               Eigen::Matrix2d* h_m) {
  const double dx = m.x() - robot.x(), dy = m.y() - robot.y();
  const double q = std::max(dx * dx + dy * dy, 1e-12), r = std::sqrt(q);
  *h_m << dx / r, dy / r, -dy / q, dx / q;
  *h_r << -dx / r, -dy / r, 0.0, dy / q, -dx / q, -1.0;
}

bool EkfSlam::JosephUpdate(Eigen::VectorXd* x, Eigen::MatrixXd* p, int slot, const Eigen::Vector2d& z,
                           const Eigen::Matrix2d& r, bool landmark_only) {
  const int j = 3 + 2 * slot;
  const Eigen::Vector3d robot = x->head<3>();
  const Eigen::Vector2d m = x->segment<2>(j);
  Eigen::Matrix<double, 2, 3> h_r;
  Eigen::Matrix2d h_m;
  MeasureJacobians(robot, m, &h_r, &h_m);
  // H P (2 x n) from the two non-zero blocks of H.
  const Eigen::MatrixXd hp = h_r * p->topRows(3) + h_m * p->middleRows(j, 2);
  const Eigen::Matrix2d s = hp.leftCols(3) * h_r.transpose() + hp.middleCols(j, 2) * h_m.transpose() + r;
  const Eigen::LLT<Eigen::Matrix2d> llt(s);
  if (llt.info() != Eigen::Success) return false;
  // K = P H^T S^-1 = (H P)^T S^-1 (P symmetric).
  Eigen::MatrixXd k = llt.solve(hp).transpose();
  if (landmark_only) {
    const Eigen::Matrix2d k_m = k.middleRows(j, 2);
    k.setZero();
    k.middleRows(j, 2) = k_m;
  }
  Eigen::Vector2d nu = z - Measure(robot, m);
  nu(1) = WrapAngle(nu(1));
  *x += k * nu;
  (*x)(2) = WrapAngle((*x)(2));
  JosephCovariance(p, k, hp, r, [&](const Eigen::MatrixXd& a) -> Eigen::MatrixXd {
    return a.leftCols(3) * h_r.transpose() + a.middleCols(j, 2) * h_m.transpose();
  });
  return true;
}

void EkfSlam::Predict(const common::SensorStep& step) {
  const int n = static_cast<int>(x_.size());
  Eigen::Matrix2d q_u = Eigen::Matrix2d::Zero();
  q_u(0, 0) = odometry_.v_noise_sd_mps * odometry_.v_noise_sd_mps;
  q_u(1, 1) = odometry_.w_noise_sd_radps * odometry_.w_noise_sd_radps;
  auto segment = [&](double v, double w, double dt) {
    // The unicycle step f(R) with its Jacobians F (pose) and G (v, w).
    const common::LinearizedUnicycleStep j =
        common::UnicycleStepWithJacobians(common::Pose2::FromVector(x_.head<3>()), v, w, dt);
    x_.head<3>() = j.next.Vector();
    const Eigen::Matrix3d p_rr = p_.topLeftCorner<3, 3>();
    p_.topLeftCorner<3, 3>() = j.f * p_rr * j.f.transpose() + j.g * q_u * j.g.transpose();
    if (n > 3) {
      const Eigen::MatrixXd p_rm = j.f * p_.topRightCorner(3, n - 3);
      p_.topRightCorner(3, n - 3) = p_rm;
      p_.bottomLeftCorner(n - 3, 3) = p_rm.transpose();
    }
  };
  bool any = false;
  for (const auto& s : step.odometry.segments) {
    if (std::isfinite(s.v_mps) && std::isfinite(s.w_radps) && s.dt_s > 0.0) {
      segment(s.v_mps, s.w_radps, s.dt_s);
      any = true;
    }
  }
  if (!any) segment(0.0, 0.0, step_dt_s_);
  p_.topLeftCorner<3, 3>() += noise_.robot_process_var.asDiagonal();
}

double EkfSlam::AssociationD2(const Detection& det, int s, Eigen::Matrix2d* s_out, Eigen::Vector2d* nu_out) const {
  const int j = 3 + 2 * s;
  const Eigen::Vector3d robot = x_.head<3>();
  const Eigen::Vector2d m = x_.segment<2>(j);
  Eigen::Matrix<double, 2, 3> h_r;
  Eigen::Matrix2d h_m;
  MeasureJacobians(robot, m, &h_r, &h_m);
  // S = H_R P_RR H_R^T + H_R P_Rm H_m^T + H_m P_mR H_R^T + H_m P_mm H_m^T + R.
  const Eigen::Matrix<double, 3, 2> p_rm = p_.block<3, 2>(0, j);
  const Eigen::Matrix2d cross = h_r * p_rm * h_m.transpose();
  const Eigen::Matrix2d innovation_cov = h_r * p_.topLeftCorner<3, 3>() * h_r.transpose() + cross + cross.transpose() +
                                         h_m * p_.block<2, 2>(j, j) * h_m.transpose() + r_;
  if (s_out != nullptr) *s_out = innovation_cov;
  Eigen::Vector2d nu = Eigen::Vector2d(det.range_m, det.bearing_rad) - Measure(robot, m);
  nu(1) = WrapAngle(nu(1));
  if (nu_out != nullptr) *nu_out = nu;
  const auto d2 = common::MahalanobisSquared<2>(nu, innovation_cov);
  return d2 ? *d2 : std::numeric_limits<double>::infinity();
}

void EkfSlam::SightPoint(const Detection& det, Eigen::Vector2d* point, Eigen::Matrix2d* cov) const {
  const Sighting g = Sight(x_.head<3>(), det.range_m, det.bearing_rad);
  *point = g.l;
  *cov = g.g_r * p_.topLeftCorner<3, 3>() * g.g_r.transpose() + g.g_z * r_ * g.g_z.transpose();
}

TimedSighting EkfSlam::SensorSighting(const Detection& det) const {
  const Sighting g = Sight(x_.head<3>(), det.range_m, det.bearing_rad);
  return {time_s_, g.l, g.g_z * r_ * g.g_z.transpose()};
}

void EkfSlam::AddLandmark(const Detection& det, std::uint32_t track_id, int landmark_id, int origin_robot,
                          std::uint32_t origin_track, bool moving) {
  const int n = static_cast<int>(x_.size());
  const Sighting g = Sight(x_.head<3>(), det.range_m, det.bearing_rad);
  const Eigen::Matrix<double, 2, 3>& g_r = g.g_r;
  const Eigen::Matrix2d& g_z = g.g_z;
  // P_mX = G_R P_RX (full cross-covariance), P_mm = G_R P_RR G_R^T + G_z R G_z^T.
  const Eigen::MatrixXd p_mx = g_r * p_.topRows(3);
  const Eigen::Matrix2d p_mm = g_r * p_.topLeftCorner<3, 3>() * g_r.transpose() + g_z * r_ * g_z.transpose();
  x_.conservativeResize(n + 2);
  x_.segment<2>(n) = g.l;
  p_.conservativeResize(n + 2, n + 2);
  p_.block(n, 0, 2, n) = p_mx;
  p_.block(0, n, n, 2) = p_mx.transpose();
  p_.block<2, 2>(n, n) = p_mm;
  Slot slot;
  slot.track_id = track_id;
  slot.landmark_id = landmark_id;
  slot.origin_robot = origin_robot;
  slot.origin_track = origin_track;
  slot.first_seen_step = step_;
  slot.last_seen_step = step_;
  slot.moving = moving;
  if (moving) slot.probation_sightings.push_back(SensorSighting(det));
  slots_.push_back(slot);
}

void EkfSlam::AppendIndependent(const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov, std::uint32_t track_id,
                                const MapLandmark& peer) {
  const int n = static_cast<int>(x_.size());
  x_.conservativeResize(n + 2);
  x_.segment<2>(n) = mean;
  p_.conservativeResize(n + 2, n + 2);
  p_.block(n, 0, 2, n).setZero();
  p_.block(0, n, n, 2).setZero();
  p_.block<2, 2>(n, n) = 0.5 * (cov + cov.transpose());
  Slot slot;
  slot.track_id = track_id;
  slot.landmark_id = peer.landmark_id;
  slot.origin_robot = peer.origin_robot;
  slot.origin_track = peer.origin_track;
  slot.first_seen_step = step_;
  slot.last_seen_step = step_;
  slots_.push_back(slot);
}

void EkfSlam::RemoveSlots(std::vector<int> slots) {
  if (slots.empty()) return;
  std::sort(slots.begin(), slots.end());
  slots.erase(std::unique(slots.begin(), slots.end()), slots.end());
  // Marginalizing a Gaussian over some components = dropping their rows and columns.
  std::vector<int> keep = {0, 1, 2};
  std::vector<Slot> kept_slots;
  std::size_t next = 0;
  for (int s = 0; s < NumSlots(); ++s) {
    if (next < slots.size() && slots[next] == s) {
      ++next;
      continue;
    }
    keep.push_back(3 + 2 * s);
    keep.push_back(4 + 2 * s);
    kept_slots.push_back(std::move(slots_[s]));
  }
  const Eigen::VectorXd x = x_(keep);
  const Eigen::MatrixXd p = p_(keep, keep);
  x_ = x;
  p_ = p;
  slots_ = std::move(kept_slots);
}

bool EkfSlam::ExpectedInView(int s) const {
  const Eigen::Vector2d m = x_.segment<2>(3 + 2 * s);
  const Eigen::Vector2d h = Measure(x_.head<3>(), m);
  Eigen::Matrix2d cov;
  AssociationD2({h(0), h(1), -1}, s, &cov);
  // Inside the reach with a 3-sigma margin on the predicted range and bearing.
  const double margin_r = 3.0 * std::sqrt(cov(0, 0)), margin_b = 3.0 * std::sqrt(cov(1, 1));
  if (h(0) + margin_r > lidar_.max_range_m || h(0) - margin_r < lidar_.min_range_m) return false;
  if (lidar_.fov_rad < 2.0 * kPi && std::abs(h(1)) + margin_b > 0.5 * lidar_.fov_rad) return false;
  return true;
}

void EkfSlam::Restart(int s, const Detection& det, std::vector<int>* removals) {
  removals->push_back(s);
  restarts_.push_back({det, slots_[s].track_id, slots_[s].landmark_id, slots_[s].origin_robot, slots_[s].origin_track});
  if (slots_[s].moving) return;
  Eigen::Vector2d point;
  Eigen::Matrix2d cov;
  SightPoint(det, &point, &cov);
  moved_.push_back({step_, slots_[s].track_id, slots_[s].landmark_id, point});
}

void EkfSlam::HandleLeftovers(const std::vector<Detection>& detections, std::vector<std::uint8_t>* det_used,
                              const std::vector<std::uint8_t>& slot_done, std::vector<int>* removals) {
  const double s_max = filter_.max_landmark_speed_mps * step_dt_s_;
  const double match_d2 = common::ChiSquare2Quantile(filter_.gate_probability);
  // Candidates (d2, distance, detection, slot) for the unmatched slots: a map landmark expected
  // in view (a ghost), one on probation wherever it is. The position residual e = g(R, z) - m
  // with covariance C = Cov(g(R, z)) + P_mm, less a motion of unknown direction of at most
  // s_max * frames (frames since last seen, at most kMaxGhostMotionFrames for a map landmark):
  //   e' = e max(0, 1 - s_max frames / |e|),  d2 = e'^T C^-1 e'  (0 within the reach of motion),
  // nearest first among equal d2.
  std::vector<std::tuple<double, double, int, int>> candidates;
  std::vector<std::uint8_t> ghost(NumSlots(), 0);
  for (int s = 0; s < NumSlots(); ++s) ghost[s] = !slot_done[s] && (slots_[s].moving || ExpectedInView(s));
  for (int d = 0; d < static_cast<int>(detections.size()); ++d) {
    if ((*det_used)[d]) continue;
    Eigen::Vector2d point;
    Eigen::Matrix2d cov;
    SightPoint(detections[d], &point, &cov);
    for (int s = 0; s < NumSlots(); ++s) {
      if (!ghost[s]) continue;
      int frames = static_cast<int>(step_ - slots_[s].last_seen_step);
      if (!slots_[s].moving) frames = std::min(kMaxGhostMotionFrames, frames);
      const Eigen::Vector2d e = point - x_.segment<2>(3 + 2 * s);
      const double distance = e.norm();
      const Eigen::Vector2d rest = e * std::max(0.0, 1.0 - s_max * frames / std::max(distance, 1e-12));
      const auto d2 = common::MahalanobisSquared<2>(rest, Eigen::Matrix2d(cov + p_.block<2, 2>(3 + 2 * s, 3 + 2 * s)));
      if (d2 && *d2 <= match_d2) candidates.emplace_back(*d2, distance, d, s);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<std::uint8_t> slot_used(NumSlots(), 0);
  for (const auto& [d2, distance, d, s] : candidates) {
    if ((*det_used)[d] || slot_used[s]) continue;
    slot_used[s] = 1;
    (*det_used)[d] = 1;
    // The landmark is seen outside its expected area: it moved.
    ++matched_observations_;
    ++flagged_observations_;
    Restart(s, detections[d], removals);
  }
}

std::vector<EkfSlam::Detection> EkfSlam::SortedDetections(const common::LidarScan& scan) {
  // Valid detections sorted by (range, bearing, id): the result does not depend on scan order.
  std::vector<Detection> detections;
  for (const auto& d : scan.landmarks) {
    if (std::isfinite(d.range_m) && std::isfinite(d.bearing_rad) && d.range_m > 0.0) {
      detections.push_back({d.range_m, WrapAngle(d.bearing_rad), d.landmark_id});
    }
  }
  std::sort(detections.begin(), detections.end(), [](const Detection& a, const Detection& b) {
    return std::tie(a.range_m, a.bearing_rad, a.landmark_id) < std::tie(b.range_m, b.bearing_rad, b.landmark_id);
  });
  return detections;
}

EkfSlam::Association EkfSlam::Associate(const std::vector<Detection>& detections) const {
  const int num_det = static_cast<int>(detections.size());
  const int num_slots = NumSlots();
  // Identities first, then nearest neighbours by increasing d2, the map landmarks before those
  // on probation (which take only the detections the map leaves).
  Association a;
  a.min_d2.assign(num_det, std::numeric_limits<double>::infinity());
  a.det_used.assign(num_det, 0);
  a.slot_done.assign(num_slots, 0);
  std::vector<std::tuple<bool, double, int, int>> candidates;  // (on probation, d2, detection, slot)
  for (int d = 0; d < num_det; ++d) {
    if (detections[d].landmark_id >= 0) {
      for (int s = 0; s < num_slots; ++s) {
        if (slots_[s].landmark_id == detections[d].landmark_id && !a.slot_done[s]) {
          a.matches.emplace_back(d, s);
          a.det_used[d] = a.slot_done[s] = 1;
          break;
        }
      }
      if (a.det_used[d]) continue;
    }
    for (int s = 0; s < num_slots; ++s) {
      if (detections[d].landmark_id >= 0 && slots_[s].landmark_id >= 0) continue;
      const double d2 = AssociationD2(detections[d], s);
      a.min_d2[d] = std::min(a.min_d2[d], d2);
      if (gates_.Classify(d2) == AssociationKind::kMatched) candidates.emplace_back(slots_[s].moving, d2, d, s);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  for (const auto& [probation, d2, d, s] : candidates) {
    if (a.det_used[d] || a.slot_done[s]) continue;
    a.matches.emplace_back(d, s);
    a.det_used[d] = a.slot_done[s] = 1;
  }
  return a;
}

std::vector<bool> EkfSlam::FlagMoving(const std::vector<Detection>& detections,
                                      const std::vector<std::pair<int, int>>& matches) {
  // ELA: which matched landmarks moved? Those on probation are tested against the map's.
  std::vector<bool> moving(matches.size(), false);
  if (ela_ && !matches.empty()) {
    std::vector<ElaObservation> obs;
    obs.reserve(matches.size());
    for (const auto& [d, s] : matches) {
      obs.push_back({s, detections[d].range_m, detections[d].bearing_rad, !slots_[s].moving});
    }
    moving = ElaTest(x_, p_, obs, r_(0, 0), r_(1, 1), ela_gate_d2_).moving;
  }
  FlagDrift(detections, matches, &moving);
  EndProbation(detections, matches, &moving);
  return moving;
}

void EkfSlam::FlagDrift(const std::vector<Detection>& detections, const std::vector<std::pair<int, int>>& matches,
                        std::vector<bool>* moving) {
  // Drift: a mapped landmark that stood within its area in each frame may still creep, its
  // estimate trailing it; the mean of its last ela_drift_window_frames position innovations then
  // stands out (MeanD2; a static landmark's innovations are white with covariance G_z S G_z^T).
  const int drift_window = filter_.ela_drift_window_frames;
  for (std::size_t i = 0; ela_ && drift_window > 0 && i < matches.size(); ++i) {
    const auto [d, s] = matches[i];
    Slot& slot = slots_[s];
    if ((*moving)[i] || slot.moving) continue;
    Eigen::Matrix2d innovation_cov;
    Eigen::Vector2d nu;
    AssociationD2(detections[d], s, &innovation_cov, &nu);
    const Sighting g = Sight(x_.head<3>(), detections[d].range_m, detections[d].bearing_rad);
    slot.innovations.push_back({time_s_, g.g_z * nu, g.g_z * innovation_cov * g.g_z.transpose()});
    if (static_cast<int>(slot.innovations.size()) > drift_window) slot.innovations.erase(slot.innovations.begin());
    if (static_cast<int>(slot.innovations.size()) == drift_window && MeanD2(slot.innovations) > ela_gate_d2_) {
      (*moving)[i] = true;
      ++creep_flags_;
    }
  }
}

void EkfSlam::EndProbation(const std::vector<Detection>& detections, const std::vector<std::pair<int, int>>& matches,
                           std::vector<bool>* moving) {
  // One on probation within its area has stayed there one more frame; after
  // ela_return_after_frames such frames it is back in the map if it showed no velocity meanwhile,
  // else it moved.
  for (std::size_t i = 0; i < matches.size(); ++i) {
    const auto [d, s] = matches[i];
    Slot& slot = slots_[s];
    if ((*moving)[i] || !slot.moving) continue;
    slot.probation_sightings.push_back(SensorSighting(detections[d]));
    if (++slot.stay_frames < filter_.ela_return_after_frames) continue;
    if (VelocityD2(slot.probation_sightings) > ela_gate_d2_) {
      (*moving)[i] = true;
      ++creep_flags_;
      continue;
    }
    slot.moving = false;
    slot.stay_frames = 0;
    slot.probation_sightings.clear();
  }
}

void EkfSlam::Correct(const std::vector<Detection>& detections, const std::vector<std::pair<int, int>>& matches,
                      const std::vector<bool>& moving) {
  // Correction with the map landmarks that stood still. Where landmarks creep (the share of the
  // observations flagged by the drift or the velocity test so far, with kCreepSharePriorObservations
  // unflagged ones as a prior, has reached ela_young_creep_share), a newly mapped landmark corrects
  // only itself for its first ela_young_sightings sightings: a creeper that has not yet stood out
  // does not drag the pose.
  const bool landmarks_creep =
      static_cast<double>(creep_flags_) >=
      filter_.ela_young_creep_share * static_cast<double>(matched_observations_ + kCreepSharePriorObservations);
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (moving[i]) continue;
    const auto [d, s] = matches[i];
    Slot& slot = slots_[s];
    slot.last_seen_step = step_;
    slot.misses = 0;
    if (!slot.moving) {
      const bool young = ela_ && landmarks_creep && slot.corrections < filter_.ela_young_sightings;
      JosephUpdate(&x_, &p_, s, Eigen::Vector2d(detections[d].range_m, detections[d].bearing_rad), r_, young);
      ++slot.corrections;
    }
  }
}

void EkfSlam::ManageMap(const std::vector<Detection>& detections, Association* a, const std::vector<bool>& moving) {
  const std::vector<std::pair<int, int>>& matches = a->matches;
  std::vector<std::uint8_t>& det_used = a->det_used;
  std::vector<std::uint8_t>& slot_done = a->slot_done;
  const int num_det = static_cast<int>(detections.size());
  const int num_slots = static_cast<int>(slot_done.size());  // before this step's removals
  std::vector<int> removals;
  restarts_.clear();
  if (ela_) {
    for (std::size_t i = 0; i < matches.size(); ++i) {
      // A map landmark moved once it has been seen outside ela_outside_frames_to_move times in a
      // row (frames it is not seen in do not break the run; the sightings outside are not used for
      // correction, but it was seen); one on probation at once. A drift flag is confirmed by the
      // next frame's window, which shares all but one innovation with it.
      Slot& slot = slots_[matches[i].second];
      if (!slot.moving) {
        slot.outside_frames = moving[i] ? slot.outside_frames + 1 : 0;
        if (slot.outside_frames < filter_.ela_outside_frames_to_move) {
          slot.last_seen_step = step_;
          slot.misses = 0;
          continue;
        }
      }
      if (moving[i]) Restart(matches[i].second, detections[matches[i].first], &removals);
    }
    HandleLeftovers(detections, &det_used, slot_done, &removals);
    for (const int s : removals) slot_done[s] = 1;
  }
  const int drop_after = ela_ ? filter_.ela_drop_unseen_after_frames : filter_.drop_after_misses;
  for (int s = 0; s < num_slots; ++s) {
    if (slot_done[s]) continue;
    // A landmark on probation not seen for drop_after_misses frames is forgotten.
    if (slots_[s].moving) {
      if (static_cast<int>(step_ - slots_[s].last_seen_step) >= filter_.drop_after_misses) removals.push_back(s);
      continue;
    }
    if (!ExpectedInView(s)) continue;
    if (++slots_[s].misses >= drop_after) removals.push_back(s);
  }
  // New landmarks are started from the pose before the removals (removals do not change it).
  std::vector<Detection> fresh;
  for (int d = 0; d < num_det; ++d) {
    if (det_used[d]) continue;
    if (detections[d].landmark_id >= 0 || gates_.Classify(a->min_d2[d]) == AssociationKind::kNew) {
      fresh.push_back(detections[d]);
    }
  }
  RemoveSlots(removals);
  for (const auto& r : restarts_) {
    AddLandmark(r.detection, r.track_id, r.landmark_id, r.origin_robot, r.origin_track, /*moving=*/true);
  }
  for (const auto& det : fresh) {
    const std::uint32_t id = next_track_id_++;
    AddLandmark(det, id, det.landmark_id, robot_index_, id, /*moving=*/false);
  }
}

void EkfSlam::Process(const common::SensorStep& step) {
  step_ = step.lidar.stamp.step;
  time_s_ = step.lidar.stamp.time_s;
  Predict(step);
  const std::vector<Detection> detections = SortedDetections(step.lidar);
  Association association = Associate(detections);
  matched_observations_ += static_cast<std::int64_t>(association.matches.size());
  const std::vector<bool> moving = FlagMoving(detections, association.matches);
  flagged_observations_ += std::count(moving.begin(), moving.end(), true);
  Correct(detections, association.matches, moving);
  ManageMap(detections, &association, moving);
}

void EkfSlam::Io(common::Archive& ar) {
  ar(x_, p_, slots_, moved_, restarts_, step_, time_s_, next_track_id_, matched_observations_, flagged_observations_,
     creep_flags_);
}

std::size_t EkfSlam::EstimatorBytes() const {
  std::size_t bytes = sizeof(*this) + sizeof(double) * static_cast<std::size_t>(x_.size() + p_.size()) +
                      ElementBytes(slots_) + ElementBytes(moved_) + ElementBytes(restarts_);
  for (const Slot& s : slots_) bytes += ElementBytes(s.probation_sightings) + ElementBytes(s.innovations);
  return bytes;
}

FilterEstimate EkfSlam::Estimate() const {
  FilterEstimate e;
  e.step = step_;
  e.time_s = time_s_;
  e.pose = common::Pose2::FromVector(x_.head<3>());
  e.covariance = p_.topLeftCorner<3, 3>();
  // Landmarks on probation are not part of the map: reported as moving and tentative.
  for (int s = 0; s < NumSlots(); ++s) {
    MapLandmark l;
    l.track_id = slots_[s].track_id;
    l.landmark_id = slots_[s].landmark_id;
    l.origin_robot = slots_[s].origin_robot;
    l.origin_track = slots_[s].origin_track;
    l.mean << x_.segment<2>(3 + 2 * s), 0.0;
    l.covariance.setZero();
    l.covariance.topLeftCorner<2, 2>() = p_.block<2, 2>(3 + 2 * s, 3 + 2 * s);
    l.covariance(2, 2) = kUnknownHeadingVar;
    l.moving = l.tentative = slots_[s].moving;
    l.first_seen_step = slots_[s].first_seen_step;
    l.last_seen_step = slots_[s].last_seen_step;
    e.landmarks.push_back(l);
  }
  return e;
}

int EkfSlam::MergeLandmarks(const std::vector<MapLandmark>& landmarks_in_own_frame, MapFusionRule rule,
                            double gate_probability, double too_close_m) {
  std::vector<MatchCandidate> own, incoming;
  std::vector<int> own_slot;  // the map landmarks (not those on probation)
  std::vector<const MapLandmark*> usable;
  for (int s = 0; s < NumSlots(); ++s) {
    if (slots_[s].moving) continue;
    own.push_back({x_.segment<2>(3 + 2 * s), p_.block<2, 2>(3 + 2 * s, 3 + 2 * s), slots_[s].landmark_id,
                   OriginKey(slots_[s].origin_robot, slots_[s].origin_track), /*stationary=*/true});
    own_slot.push_back(s);
  }
  for (const auto& l : landmarks_in_own_frame) {
    const Eigen::Matrix2d c = l.covariance.topLeftCorner<2, 2>();
    if (l.moving || !l.mean.head<2>().allFinite() || !common::IsSymmetricPositiveDefinite<2>(c)) continue;
    usable.push_back(&l);
    incoming.push_back({l.mean.head<2>(), c, l.landmark_id, OriginKey(l.origin_robot, l.origin_track),
                        /*stationary=*/true});
  }
  const std::vector<int> match =
      MatchLandmarks(own, incoming, common::ChiSquare2Quantile(gate_probability), too_close_m);
  int added = 0;
  for (std::size_t i = 0; i < usable.size(); ++i) {
    if (match[i] == kTooClose) continue;
    const Eigen::Vector2d z = incoming[i].position;
    const Eigen::Matrix2d r = incoming[i].covariance;
    if (match[i] < 0) {
      AppendIndependent(z, r, next_track_id_++, *usable[i]);
      ++added;
      continue;
    }
    // The fused estimate starts the drift and outside counts afresh.
    slots_[own_slot[match[i]]].innovations.clear();
    slots_[own_slot[match[i]]].outside_frames = 0;
    // A position observation of slot j: H = [0 .. I .. 0], H P = P rows j, j+1.
    const int j = 3 + 2 * own_slot[match[i]];
    const int n = static_cast<int>(x_.size());
    Eigen::Matrix2d r0 = r;
    if (rule == MapFusionRule::kCovarianceIntersection) {
      // omega minimizing det((omega P_mm^-1 + (1 - omega) r^-1)^-1), on a grid. Full CI would
      // update P / omega with r / (1 - omega); inflating the whole joint covariance by 1 / omega
      // at every merged landmark compounds over a snapshot, so only the incoming estimate is
      // de-weighted (r / (1 - omega)) and P is kept.
      const Eigen::Matrix2d info_m = p_.block<2, 2>(j, j).inverse(), info_r = r.inverse();
      double best = 0.5, best_det = std::numeric_limits<double>::infinity();
      for (int g = 1; g < 20; ++g) {
        const double w = 0.05 * g;
        const double det = (w * info_m + (1.0 - w) * info_r).inverse().determinant();
        if (det < best_det) {
          best_det = det;
          best = w;
        }
      }
      r0 = r / (1.0 - best);
    }
    const Eigen::MatrixXd hp = p_.middleRows(j, 2);
    Eigen::MatrixXd k;
    if (rule == MapFusionRule::kAverage) {
      k = Eigen::MatrixXd::Zero(n, 2);
      k.block<2, 2>(j, 0) = 0.5 * Eigen::Matrix2d::Identity();
    } else {
      const Eigen::Matrix2d s = hp.middleCols(j, 2) + r0;
      k = s.llt().solve(hp).transpose();
    }
    x_ += k * (z - x_.segment<2>(j));
    x_(2) = WrapAngle(x_(2));
    JosephCovariance(&p_, k, hp, r0, [&](const Eigen::MatrixXd& a) -> Eigen::MatrixXd { return a.middleCols(j, 2); });
  }
  return added;
}

std::vector<MovedLandmark> EkfSlam::TakeMovedLandmarks() {
  std::vector<MovedLandmark> out;
  out.swap(moved_);
  return out;
}

bool EkfSlam::ApplyMovedNotice(const Eigen::Vector2d& position, const Eigen::Matrix2d& cov, double gate_probability) {
  const double gate = common::ChiSquare2Quantile(gate_probability);
  int best = -1;
  double best_d2 = gate;
  for (int s = 0; s < NumSlots(); ++s) {
    if (slots_[s].moving) continue;
    const auto d2 = common::MahalanobisSquared<2>(Eigen::Vector2d(x_.segment<2>(3 + 2 * s) - position),
                                                  Eigen::Matrix2d(p_.block<2, 2>(3 + 2 * s, 3 + 2 * s) + cov));
    if (d2 && *d2 <= best_d2) {
      best_d2 = *d2;
      best = s;
    }
  }
  if (best < 0) return false;
  RemoveSlots({best});
  return true;
}

std::unique_ptr<SlamFilter> CreateEkfSlam(const AgentOptions& options, bool ela) {
  return std::make_unique<EkfSlam>(options, ela);
}

}  // namespace mrslam::robot_agent::filters
