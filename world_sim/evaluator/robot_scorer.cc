#include "world_sim/evaluator/robot_scorer.h"

#include <cmath>
#include <string>

#include <Eigen/Cholesky>

#include "common/angles.h"
#include "common/gaussian.h"

namespace mrslam::evaluator {

RobotScorer::RobotScorer(const common::Pose2& frame_in_world, const common::Pose2& dead_reckoning_start,
                         const common::LidarOptions& lidar, int robot_index)
    : frame_(frame_in_world), dead_reckoning_(dead_reckoning_start), lidar_(lidar), robot_index_(robot_index) {}

bool InLidarReach(const common::LidarOptions& lidar, const common::Pose2& pose, const Eigen::Vector2d& point) {
  const auto z = common::MeasureRangeBearing(pose, point);
  return z.range_m <= lidar.max_range_m && std::abs(z.bearing_rad) <= lidar.fov_rad / 2.0;
}

StepScore RobotScorer::Add(const common::GroundTruth& truth, const common::Pose2& robot_truth,
                           const common::Pose2& pose, const std::optional<Eigen::Matrix3d>& covariance,
                           const std::vector<MapPoint>& landmarks, const common::Odometry* odometry) {
  StepScore s;
  s.truth_own = TruthInOwnFrame(robot_truth, frame_);
  s.position_err_m = PositionError(pose, s.truth_own);
  s.heading_err_rad = HeadingError(pose, s.truth_own);
  s.nees = covariance ? PoseNees(pose, *covariance, s.truth_own) : std::nan("");
  position_err_.Add(s.position_err_m);
  heading_err_deg_.Add(common::DegFromRad(s.heading_err_rad));
  if (std::isfinite(s.nees)) {
    nees_sum_ += s.nees;
    ++nees_count_;
  }
  if (odometry != nullptr) {
    for (const auto& g : odometry->segments) {
      dead_reckoning_ = common::UnicycleStep(dead_reckoning_, g.v_mps, g.w_radps, g.dt_s);
    }
    dead_reckoning_err_.Add(PositionError(dead_reckoning_, s.truth_own));
  }
  std::vector<TruePoint> true_points;
  std::vector<bool> moving;
  for (const auto& l : truth.landmarks) {
    true_points.push_back({l.pose.Translation(), std::stoi(l.id)});
    moving.push_back(l.moving);
    if (InLidarReach(lidar_, robot_truth, l.pose.Translation())) {
      seen_.insert(true_points.back().landmark_id);
      if (l.moving) seen_moving_.insert(true_points.back().landmark_id);
    }
  }
  in_map_.clear();
  const std::vector<LandmarkMatch> matches = MatchLandmarks(landmarks, true_points, frame_);
  for (std::size_t i = 0; i < matches.size(); ++i) {
    const LandmarkMatch& match = matches[i];
    s.landmark_errors_m.push_back(match.error_m);
    const bool mover = match.truth_index >= 0 && moving[static_cast<std::size_t>(match.truth_index)];
    (mover ? moving_landmark_err_ : static_landmark_err_).Add(match.error_m);
    if (match.truth_index < 0) continue;
    const TruePoint& truth_point = true_points[static_cast<std::size_t>(match.truth_index)];
    AddAdopted(landmarks[i], truth_point.position_m);
    const int id = truth_point.landmark_id;
    in_map_.emplace(id, landmarks[i]);
    if (seen_.count(id) > 0) own_landmark_err_.Add(match.error_m);
  }
  for (const double e : s.landmark_errors_m) landmark_err_.Add(e);
  completeness_ = Completeness(seen_);
  moving_completeness_ = Completeness(seen_moving_);
  s.map_completeness = completeness_;
  mapped_ = landmarks.size();
  return s;
}

double RobotScorer::Completeness(const std::set<int>& seen) const {
  if (seen.empty()) return 1.0;
  std::size_t kept = 0;
  for (const int id : seen) kept += in_map_.count(id);
  return static_cast<double>(kept) / static_cast<double>(seen.size());
}

void RobotScorer::AddAdopted(const MapPoint& l, const Eigen::Vector2d& truth_w) {
  if (l.origin_robot < 0 || l.origin_robot == robot_index_) return;
  if (!common::IsSymmetricPositiveDefinite<2>(l.covariance_m2)) return;
  const Eigen::Vector2d e = l.position_m - common::TransformPoint(common::Inverse(frame_), truth_w);
  adopted_nees_sum_ += e.dot(l.covariance_m2.ldlt().solve(e));
  ++adopted_nees_count_;
}

RobotSummary RobotScorer::Summary() const {
  RobotSummary r;
  r.position_rmse_m = position_err_.Value();
  r.heading_rmse_deg = heading_err_deg_.Value();
  r.landmark_rmse_m = landmark_err_.Value();
  r.static_landmark_rmse_m = static_landmark_err_.Value();
  r.moving_landmark_rmse_m = moving_landmark_err_.Value();
  r.own_landmark_rmse_m = own_landmark_err_.Value();
  r.dead_reckoning_rmse_m = dead_reckoning_err_.Value();
  r.mean_nees = nees_count_ == 0 ? 0.0 : nees_sum_ / static_cast<double>(nees_count_);
  r.adopted_landmark_nees =
      adopted_nees_count_ == 0 ? std::nan("") : adopted_nees_sum_ / static_cast<double>(adopted_nees_count_);
  r.landmarks_mapped = mapped_;
  r.map_completeness = completeness_;
  r.moving_completeness = moving_completeness_;
  r.steps_scored = position_err_.count();
  return r;
}

}  // namespace mrslam::evaluator
