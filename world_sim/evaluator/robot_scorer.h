#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "common/sensor_options.h"
#include "common/sensor_types.h"
#include "world_sim/evaluator/metrics.h"

namespace mrslam::evaluator {

// What one step of one robot scored (docs/metrics.md), in the robot's own frame G_i.
struct StepScore {
  common::Pose2 truth_own;  // the true pose in G_i
  double position_err_m = 0.0;
  double heading_err_rad = 0.0;
  double nees = 0.0;  // NaN without a usable covariance
  std::vector<double> landmark_errors_m;
  double map_completeness = 1.0;  // so far
};

// One robot's accuracy over a run, as summary.json reports it.
struct RobotSummary {
  double position_rmse_m = 0.0;
  double heading_rmse_deg = 0.0;
  double landmark_rmse_m = 0.0;  // 0 when the map never held a landmark
  // The same split by what each map landmark stands for: a static or a moving true landmark (a
  // map landmark with no true partner counts as static: it corrupts the static map).
  double static_landmark_rmse_m = 0.0;
  double moving_landmark_rmse_m = 0.0;
  // Over the map landmarks whose true partner the robot itself has had within its lidar's reach
  // by then (what it could have observed, not what peers handed it; one matched to a landmark
  // never in reach, or to none, is left out; 0 when none is left).
  double own_landmark_rmse_m = 0.0;
  // The mean position NEES (2 dof) of the map landmarks taken from other robots (their
  // provenance names another robot), over the steps and those with a true partner and a
  // positive definite covariance; NaN when there were none.
  double adopted_landmark_nees = 0.0;
  double dead_reckoning_rmse_m = 0.0;  // over the steps with odometry
  double mean_nees = 0.0;              // over the steps with a finite NEES; 0 for none
  std::size_t landmarks_mapped = 0;    // at the last step
  double map_completeness = 1.0;       // at the last step
  double moving_completeness = 1.0;    // the same over the moving landmarks only
  std::size_t steps_scored = 0;
};

// Whether a landmark at point is within the lidar's reach (range and field of view) of a robot at
// pose (true poses).
bool InLidarReach(const common::LidarOptions& lidar, const common::Pose2& pose, const Eigen::Vector2d& point);

// Scores one robot step by step against the truth: the single definition of the accuracy
// metrics (docs/metrics.md) that the evaluator and the batch tools share. Pure.
class RobotScorer {
 public:
  // frame_in_world: the robot's own frame G_i; dead_reckoning_start: its first pose in G_i; the
  // lidar's reach decides which landmarks the robot could have sensed; robot_index: its index in
  // the scenario (the provenance of the landmarks it mapped itself), -1 if unknown.
  RobotScorer(const common::Pose2& frame_in_world, const common::Pose2& dead_reckoning_start,
              const common::LidarOptions& lidar, int robot_index = -1);

  // One step: the truth (robot_truth: this robot's true pose in W), the estimate in G_i (without
  // a covariance the NEES is not scored) and the step's odometry, if any, which advances the
  // dead reckoning.
  StepScore Add(const common::GroundTruth& truth, const common::Pose2& robot_truth, const common::Pose2& pose,
                const std::optional<Eigen::Matrix3d>& covariance, const std::vector<MapPoint>& landmarks,
                const common::Odometry* odometry);

  RobotSummary Summary() const;
  // The true landmarks that stand in the map at the last step: by id, the map landmark standing
  // for each.
  const std::map<int, MapPoint>& InMap() const { return in_map_; }
  // The true landmarks seen moving within the robot's reach so far.
  const std::set<int>& SeenMoving() const { return seen_moving_; }
  // The share of the true landmarks `seen` that stand in the map at the last step (1 for none).
  double Completeness(const std::set<int>& seen) const;

 private:
  common::Pose2 frame_;
  common::Pose2 dead_reckoning_;
  common::LidarOptions lidar_;
  int robot_index_ = -1;
  // Adds the NEES of map landmark l against the true point truth_w (world frame) if it was taken
  // from another robot.
  void AddAdopted(const MapPoint& l, const Eigen::Vector2d& truth_w);

  // Running figures only: the scorer's memory does not grow with the run.
  RunningRmse position_err_, heading_err_deg_, landmark_err_, dead_reckoning_err_;
  RunningRmse static_landmark_err_, moving_landmark_err_, own_landmark_err_;
  double nees_sum_ = 0.0;
  std::size_t nees_count_ = 0;
  double adopted_nees_sum_ = 0.0;
  std::size_t adopted_nees_count_ = 0;
  std::set<int> seen_;              // true landmark ids ever within the robot's reach
  std::set<int> seen_moving_;       // the moving ones among them
  std::map<int, MapPoint> in_map_;  // InMap()
  double completeness_ = 1.0, moving_completeness_ = 1.0;
  std::size_t mapped_ = 0;
};

}  // namespace mrslam::evaluator
