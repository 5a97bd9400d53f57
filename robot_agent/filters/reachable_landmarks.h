#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "robot_agent/filters/landmark_ekf.h"

namespace mrslam::robot_agent::filters {

// What decides whether a landmark can gate with a step's readings (GateBlock's d2 at most
// `gate`). A reading of range z gates a landmark at range r from the pose only if
//   (z - r)^2 <= gate * S_rr,  S_rr <= tr(P_pp) + tr(Sigma_pp) + var_r
// (d2 >= nu_r^2 / S_rr for S positive definite; Euclidean gating: d2 >= nu_r^2, so S_rr = 1):
// the landmarks outside the ring [z_min - reach, z_max + reach] around the pose cannot.
struct ReachRule {
  double gate = 0.0;
  double var_r = 0.0;
  double var_b = 0.0;  // for the gating itself
  bool euclidean = false;
  double shift_m = 0.0;  // how far the pose may move before the landmarks are gathered again
};

// The lanes (bit l for lane l) of a block's first `count` landmarks that a reading of range in
// [z_min, z_max] can gate from any pose within rule.shift_m of xy whose position covariance has
// a trace at most pose_var_xy. A slack of 1e-6 relative covers the kernels' rounding.
template <int D>
std::uint32_t ReachableLanes(const LandmarkBlock<D>& block, int count, const Eigen::Vector2d& xy, double pose_var_xy,
                             double z_min, double z_max, const ReachRule& rule);

// One particle's landmarks that the step's readings can gate, their positions and position
// covariances (all that gating reads) copied into blocks of their own in slot order (so that
// ties are broken as over all of them), and gated from there: a step's readings see only the
// landmarks within the lidar's range of the robot, and gating every landmark of every particle
// for every reading was the step's largest cost on large maps.
// Gathered again when the proposal moves by more than rule.shift_m or its position variance
// grows (a FastSLAM 2.0 proposal moves and shrinks with each matched reading).
template <int D>
class ReachableLandmarks {
 public:
  explicit ReachableLandmarks(const ReachRule& rule) : rule_(rule) {}

  // The range of the step's readings; forgets the particle gathered last.
  void StartStep(double z_min, double z_max);
  // Forgets the particle gathered last (the next one is another).
  void Reset() { valid_ = false; }
  // The unused slot (used: per slot of the particle) nearest to reading (z_r, z_b) from pose
  // with covariance sigma, and its d2; -1 when no reachable landmark is unused. Equal to
  // gating every landmark when the nearest is within the rule's gate; beyond it, the slot is
  // -1 or one whose d2 is beyond the gate too.
  std::pair<int, double> Nearest(const std::vector<std::shared_ptr<LandmarkBlock<D>>>& blocks, int count,
                                 const common::Pose2& pose, const Eigen::Matrix3d& sigma, double z_r, double z_b,
                                 const std::vector<std::uint8_t>& used);
  // Landmarks gathered at the last gathering (for tests and counts; a particle of one block is
  // gated without gathering).
  int size() const { return static_cast<int>(slots_.size()); }

 private:
  void Gather(const std::vector<std::shared_ptr<LandmarkBlock<D>>>& blocks, int count, const Eigen::Vector2d& xy,
              double pose_var_xy);
  // d2_ of the gathered landmarks (gathered first when due) for the reading.
  void GateGathered(const std::vector<std::shared_ptr<LandmarkBlock<D>>>& blocks, int count, const common::Pose2& pose,
                    const Eigen::Matrix3d& sigma, double z_r, double z_b);

  ReachRule rule_;
  double z_min_ = 0.0, z_max_ = 0.0;
  bool valid_ = false;
  Eigen::Vector2d center_ = Eigen::Vector2d::Zero();
  double pose_var_xy_ = 0.0;
  std::vector<LandmarkBlock<2>> blocks_;
  std::vector<int> slots_;  // the particle's slot of each gathered landmark
  std::vector<double> d2_;
};

}  // namespace mrslam::robot_agent::filters
