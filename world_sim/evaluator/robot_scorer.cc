#include "world_sim/evaluator/robot_scorer.h"

#include <cmath>
#include <string>

#include "common/angles.h"

namespace mrslam::evaluator {

RobotScorer::RobotScorer(const common::Pose2& frame_in_world, const common::Pose2& dead_reckoning_start,
                         const common::LidarOptions& lidar)
    : frame_(frame_in_world), dead_reckoning_(dead_reckoning_start), lidar_(lidar) {}

bool RobotScorer::InReach(const common::Pose2& pose, const Eigen::Vector2d& point) const {
  const auto z = common::MeasureRangeBearing(pose, point);
  return z.range_m <= lidar_.max_range_m && std::abs(z.bearing_rad) <= lidar_.fov_rad / 2.0;
}

StepScore RobotScorer::Add(const common::GroundTruth& truth, const common::Pose2& robot_truth,
                           const common::Pose2& pose, const std::optional<Eigen::Matrix3d>& covariance,
                           const std::vector<MapPoint>& landmarks, const common::Odometry* odometry) {
  StepScore s;
  s.truth_own = TruthInOwnFrame(robot_truth, frame_);
  s.position_err_m = PositionError(pose, s.truth_own);
  s.heading_err_rad = HeadingError(pose, s.truth_own);
  s.nees = covariance ? PoseNees(pose, *covariance, s.truth_own) : std::nan("");
  position_err_.push_back(s.position_err_m);
  heading_err_deg_.push_back(common::DegFromRad(s.heading_err_rad));
  if (std::isfinite(s.nees)) nees_.push_back(s.nees);
  if (odometry != nullptr) {
    for (const auto& g : odometry->segments) {
      dead_reckoning_ = common::UnicycleStep(dead_reckoning_, g.v_mps, g.w_radps, g.dt_s);
    }
    dead_reckoning_err_.push_back(PositionError(dead_reckoning_, s.truth_own));
  }
  std::vector<TruePoint> true_points;
  for (const auto& l : truth.landmarks) {
    true_points.push_back({l.pose.Translation(), std::stoi(l.id)});
    if (InReach(robot_truth, l.pose.Translation())) seen_.insert(true_points.back().landmark_id);
  }
  s.landmark_errors_m = LandmarkErrors(landmarks, true_points, frame_);
  landmark_err_.insert(landmark_err_.end(), s.landmark_errors_m.begin(), s.landmark_errors_m.end());
  std::size_t matched_seen = 0;
  in_map_.clear();
  for (const int j : MatchedTruth(landmarks, true_points, frame_)) {
    const int landmark_id = true_points[static_cast<std::size_t>(j)].landmark_id;
    matched_seen += seen_.count(landmark_id);
    in_map_.insert(landmark_id);
  }
  completeness_ = seen_.empty() ? 1.0 : static_cast<double>(matched_seen) / static_cast<double>(seen_.size());
  s.map_completeness = completeness_;
  mapped_ = landmarks.size();
  return s;
}

RobotSummary RobotScorer::Summary() const {
  RobotSummary r;
  r.position_rmse_m = Rmse(position_err_);
  r.heading_rmse_deg = Rmse(heading_err_deg_);
  r.landmark_rmse_m = Rmse(landmark_err_);
  r.dead_reckoning_rmse_m = Rmse(dead_reckoning_err_);
  double nees_sum = 0.0;
  for (const double v : nees_) nees_sum += v;
  r.mean_nees = nees_.empty() ? 0.0 : nees_sum / static_cast<double>(nees_.size());
  r.landmarks_mapped = mapped_;
  r.map_completeness = completeness_;
  r.steps_scored = position_err_.size();
  return r;
}

}  // namespace mrslam::evaluator
