#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/sensor_types.h"
#include "robot_agent/filters/association.h"
#include "robot_agent/filters/ela.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent::filters {

// A landmark the ELA test found moving (for "landmark moved" notices to the peers).

// Classic EKF-SLAM (filter.type ekf) and EKF-SLAM with paper B's expected-landmark-area test
// (filter.type ekf_ela). Owns the joint Gaussian over
//   x = (x_R, y_R, phi_R, m_1x, m_1y, ..., m_nx, m_ny)      (static landmark model)
// in the agent's own frame; for ekf_ela some of the m are on probation (found moving, see 6).
//
// One step (Process):
//  1. Prediction per odometry segment (v, w, dt), the unicycle of docs/models.md:
//       f(R) = (x + v dt cos(phi + w dt), y + v dt sin(phi + w dt), phi + w dt),
//       F = df/dR, G = df/d(v, w); P_RR = F P_RR F^T + G diag(sd_v^2, sd_w^2) G^T,
//       P_RM = F P_RM; after the last segment P_RR += diag(noise.robot_process_var).
//  2. Association: h(R, m) = (|m - p_R|, atan2(m_y - y_R, m_x - x_R) - phi_R), innovation
//     nu = z - h (bearing wrapped), S = H P H^T + R with H = [H_R 0 .. H_m .. 0]. Pairs with
//     d2 = nu^T S^-1 nu <= chi2_2(gate_probability) are matched greedily by increasing d2 (each
//     detection and each landmark at most once; reported identities decide when present; ekf_ela:
//     the map landmarks before those on probation). An unmatched detection beyond
//     chi2_2(new_landmark_probability) of every landmark starts one.
//  3. (ekf_ela) the ELA test (ela.h) over the matched landmarks, those on probation tested
//     against the map landmarks; those outside are not used for correction. A mapped landmark
//     within its area whose last ela_drift_window_frames position innovations G_z nu (covariance
//     G_z S G_z^T, white for a static landmark) have a weighted mean beyond the same gate
//     (MeanD2) is outside too: a creeping landmark's estimate trails it, each frame within the
//     gate. One on probation outside moved; a mapped one moved once it has been outside
//     ela_outside_frames_to_move frames in a row.
//  4. Update, one detection at a time, in Joseph form with the sparse H:
//       K = P H^T S^-1,  A = (I - K H) P = P - K (H P),
//       P = A (I - K H)^T + K R K^T = A - (A H^T) K^T + K R K^T   (O(n^2)), then symmetrized.
//  5. New landmarks by the inverse sensor model m = g(R, z) with the full cross-covariance:
//       P_mm = G_R P_RR G_R^T + G_z R G_z^T,  P_mX = G_R P_RX.
//  6. Map management. ekf: a landmark expected in view (predicted inside the sensor's reach by
//     a 3-sigma margin) but not matched drop_after_misses frames in a row is removed.
//     ekf_ela (paper B's Algorithm 1): a landmark found moving has its old information removed
//     (its rows and columns marginalized out of x) and is re-initialized at its observed position
//     by step 5, on probation: it stays in x (so its cross-covariance with the pose is kept) but
//     is not used for correction and is reported with moving = tentative = true (not part of the
//     map). Each frame it is seen, the ELA test checks it against the pose and the map landmarks
//     seen with it: outside, it is re-initialized again; inside for ela_return_after_frames frames,
//     it is back in the map if its sightings on probation show no velocity (VelocityD2 within
//     the ELA gate, ela.h), else it is re-initialized again: a slow mover stays within its area
//     for some frames, but not still. An expected but unmatched map landmark (or an unmatched one on
//     probation) that a leftover detection explains by motion (within the gate once a motion of
//     up to max_landmark_speed dt n is taken off the residual, n = frames since last seen, at
//     most 2 for a map landmark) moved too; a map landmark expected in view and not seen at all is
//     deleted after ela_drop_unseen_after_frames such frames. (Paper B's Algorithm 1 deletes the
//     landmarks expected to be sensed only in a frame without detections; with a dense field
//     there always are some, so the rule is applied per landmark; 1 = at once.) One on probation
//     not seen for drop_after_misses frames is forgotten.
//
// Not thread-safe; pure (no DDS, no wall clock).
class EkfSlam : public SlamFilter {
 public:
  EkfSlam(const AgentOptions& options, bool ela);

  void Process(const common::SensorStep& step) override;
  FilterEstimate Estimate() const override;
  void Io(common::Archive& ar) override;
  // The state x (3 + 2 n doubles for n landmarks), its covariance P ((3 + 2 n)^2 doubles: the
  // term that grows, quadratically, with the map), the landmarks' bookkeeping and their recent
  // sightings (ekf_ela), the moves not yet taken.
  std::size_t EstimatorBytes() const override;
  // Each incoming landmark is matched to the mapped ones (MatchLandmarks); a match is fused into
  // the joint state as a position observation z = m_in, H = [0 .. I .. 0], with the gain of the
  // rule (weighted: Kalman gain with R = C_in; covariance intersection: the Kalman gain with
  // R = C_in / (1 - omega), omega minimizing det of the fused landmark block — the own joint
  // covariance is not inflated by 1 / omega, which would compound over a snapshot; average:
  // K = I / 2 on the landmark rows) in Joseph form; unmatched ones (not moving) are appended
  // uncorrelated, except those too close to a mapped one (kTooClose).
  int MergeLandmarks(const std::vector<MapLandmark>& landmarks_in_own_frame, MapFusionRule rule,
                     double gate_probability, double too_close_m) override;

  // Landmarks found moving since the last call (ekf_ela), for "landmark moved" notices.
  std::vector<MovedLandmark> TakeMovedLandmarks() override;
  // A peer's notice, its position moved into the own frame: the mapped landmark nearest to it
  // within the chi-square gate (position covariance plus cov) is removed. Returns true if one was.
  bool ApplyMovedNotice(const Eigen::Vector2d& position, const Eigen::Matrix2d& cov, double gate_probability) override;

  // Introspection for tests: landmarks in the map, and on probation (ekf_ela).
  int NumMapped() const { return NumSlots() - NumMoving(); }
  int NumMoving() const {
    return static_cast<int>(std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.moving; }));
  }
  const Eigen::VectorXd& State() const { return x_; }
  const Eigen::MatrixXd& Covariance() const { return p_; }
  // Counts over the run: matched observations of mapped landmarks, and those the ELA flagged
  // moving (outside the area, drifting, or with a velocity on probation), whether or not the flag
  // has yet taken the landmark out of the map.
  std::int64_t MatchedObservations() const { return matched_observations_; }
  std::int64_t FlaggedObservations() const { return flagged_observations_; }

  // The measurement model and its Jacobians (public for tests): h(R, m) as in step 2.
  static Eigen::Vector2d Measure(const Eigen::Vector3d& robot, const Eigen::Vector2d& m);
  static void MeasureJacobians(const Eigen::Vector3d& robot, const Eigen::Vector2d& m, Eigen::Matrix<double, 2, 3>* h_r,
                               Eigen::Matrix2d* h_m);
  // One Joseph-form update of (x, p) with the measurement z of the landmark in slot (step 4);
  // returns false when S is not positive definite. With landmark_only the gain is kept on the
  // landmark's own rows (zero elsewhere): the pose and the other landmarks, means and covariance,
  // stay as they were, and the Joseph form keeps p the covariance of the estimate.
  static bool JosephUpdate(Eigen::VectorXd* x, Eigen::MatrixXd* p, int slot, const Eigen::Vector2d& z,
                           const Eigen::Matrix2d& r, bool landmark_only = false);

 private:
  struct Slot {
    std::uint32_t track_id = 0;
    int landmark_id = -1;
    int origin_robot = -1;  // provenance (MapLandmark::origin_robot, origin_track)
    std::uint32_t origin_track = 0;
    std::uint32_t first_seen_step = 0;
    std::uint32_t last_seen_step = 0;
    int misses = 0;
    bool moving = false;     // on probation (ekf_ela, step 6)
    int stay_frames = 0;     // frames on probation within its area
    int corrections = 0;     // sightings used for correction since it entered the map
    int outside_frames = 0;  // a map landmark's sightings in a row outside its area
    // Since it was put on probation: the first from that frame's corrected pose, the later ones
    // from each frame's predicted pose.
    std::vector<TimedSighting> probation_sightings;
    std::vector<TimedSighting> innovations;  // a map landmark's last position innovations

    void Io(common::Archive& ar) {
      ar(track_id, landmark_id, origin_robot, origin_track, first_seen_step, last_seen_step, misses, moving,
         stay_frames, corrections, outside_frames, probation_sightings, innovations);
    }
  };
  struct Detection {
    double range_m = 0.0;
    double bearing_rad = 0.0;
    int landmark_id = -1;
  };
  // A landmark found moving, re-initialized on probation at the end of the step.
  struct Restarting {
    Detection detection;
    std::uint32_t track_id = 0;
    int landmark_id = -1;
    int origin_robot = -1;
    std::uint32_t origin_track = 0;
  };

  int NumSlots() const { return static_cast<int>(slots_.size()); }
  void Predict(const common::SensorStep& step);
  // d2, innovation covariance and innovation of detection det against slot s.
  double AssociationD2(const Detection& det, int s, Eigen::Matrix2d* s_out = nullptr,
                       Eigen::Vector2d* nu_out = nullptr) const;
  // Appends a landmark from detection det (step 5), on probation if moving, with its provenance.
  void AddLandmark(const Detection& det, std::uint32_t track_id, int landmark_id, int origin_robot,
                   std::uint32_t origin_track, bool moving);
  // Appends a peer's landmark given as N(mean, cov), uncorrelated with x, keeping its provenance.
  void AppendIndependent(const Eigen::Vector2d& mean, const Eigen::Matrix2d& cov, std::uint32_t track_id,
                         const MapLandmark& peer);
  // Removes the slots (any order), marginalizing them out of x.
  void RemoveSlots(std::vector<int> slots);
  // The observed point g(R, z) and its covariance through the pose (no cross terms with m).
  void SightPoint(const Detection& det, Eigen::Vector2d* point, Eigen::Matrix2d* cov) const;
  // The observed point g(R, z) now, with the covariance of the sensor noise alone.
  TimedSighting SensorSighting(const Detection& det) const;
  bool ExpectedInView(int s) const;
  // ekf_ela, step 6 for the detections left over after association and the unmatched slots.
  void HandleLeftovers(const std::vector<Detection>& detections, std::vector<std::uint8_t>* det_used,
                       const std::vector<std::uint8_t>& slot_done, std::vector<int>* removals);
  // ekf_ela: slot s, seen at det, moved: it is removed and re-initialized on probation at the end
  // of the step; a map landmark's move is noted for the peers.
  void Restart(int s, const Detection& det, std::vector<int>* removals);

  // The stages of Process, in order.
  // One step's association: the matches (detection, slot) and what they used.
  struct Association {
    std::vector<std::pair<int, int>> matches;  // (detection, slot)
    std::vector<std::uint8_t> det_used, slot_done;
    std::vector<double> min_d2;  // per detection, its smallest d2 to a slot it may match
  };
  // The scan's valid detections in a fixed order.
  static std::vector<Detection> SortedDetections(const common::LidarScan& scan);
  Association Associate(const std::vector<Detection>& detections) const;
  // Per match, whether its landmark moved: the ELA test, then FlagDrift and EndProbation.
  std::vector<bool> FlagMoving(const std::vector<Detection>& detections,
                               const std::vector<std::pair<int, int>>& matches);
  // ekf_ela: a mapped landmark whose recent innovations average beyond its area moved.
  void FlagDrift(const std::vector<Detection>& detections, const std::vector<std::pair<int, int>>& matches,
                 std::vector<bool>* moving);
  // A landmark on probation that stayed long enough in its area returns to the map, unless it
  // showed a velocity meanwhile (then it moved).
  void EndProbation(const std::vector<Detection>& detections, const std::vector<std::pair<int, int>>& matches,
                    std::vector<bool>* moving);
  // The EKF update with the matched landmarks that stood still.
  void Correct(const std::vector<Detection>& detections, const std::vector<std::pair<int, int>>& matches,
               const std::vector<bool>& moving);
  // Landmarks that moved restarted on probation, missed ones dropped, new ones started.
  void ManageMap(const std::vector<Detection>& detections, Association* a, const std::vector<bool>& moving);

  const FilterOptions filter_;
  const common::LidarOptions lidar_;
  const common::OdometryOptions odometry_;
  const common::NoiseOptions noise_;
  const double step_dt_s_;
  const bool ela_;
  const AssociationGates gates_;
  const double ela_gate_d2_;
  const int robot_index_;  // in the team: the provenance of the landmarks it maps
  Eigen::Matrix2d r_;      // lidar noise diag(var_r, var_b)

  Eigen::VectorXd x_;
  Eigen::MatrixXd p_;
  std::vector<Slot> slots_;
  std::vector<MovedLandmark> moved_;
  std::vector<Restarting> restarts_;
  std::uint32_t step_ = 0;
  double time_s_ = 0.0;
  std::uint32_t next_track_id_ = 1;
  std::int64_t matched_observations_ = 0;
  std::int64_t flagged_observations_ = 0;
  std::int64_t creep_flags_ = 0;  // flags by the drift or the velocity test
};

// The ekf (ela = false) or ekf_ela (ela = true) filter for the agent of options.
std::unique_ptr<SlamFilter> CreateEkfSlam(const AgentOptions& options, bool ela);

}  // namespace mrslam::robot_agent::filters
