#include "world_sim/evaluator/paper_b_scorer.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace mrslam::evaluator {

double MeanOfFinite(const std::vector<double>& values) {
  double s = 0.0;
  int n = 0;
  for (const double x : values) {
    if (std::isfinite(x)) {
      s += x;
      ++n;
    }
  }
  return n > 0 ? s / n : std::nan("");
}

PaperBScorer::PaperBScorer(std::vector<common::Pose2> frames_in_world, double lidar_range_m)
    : frames_(std::move(frames_in_world)),
      lidar_range_m_(lidar_range_m),
      frame_rmse_(frames_.size()),
      position_sq_(frames_.size()),
      reached_(frames_.size()),
      last_map_(frames_.size()) {}

void PaperBScorer::AddFrame(const common::GroundTruth& truth, const std::vector<RobotReport>& reports) {
  true_landmarks_.clear();
  is_static_.clear();
  for (const auto& l : truth.landmarks) {
    true_landmarks_.push_back({l.pose.Translation(), std::stoi(l.id)});
    is_static_.push_back(!l.moving);
  }
  for (std::size_t i = 0; i < frames_.size(); ++i) AddRobot(i, truth, reports[i]);
}

void PaperBScorer::AddRobot(std::size_t i, const common::GroundTruth& truth, const RobotReport& report) {
  const common::Pose2 truth_own = TruthInOwnFrame(truth.robots[i].pose, frames_[i]);
  const double pe = PositionError(report.pose, truth_own);
  position_sq_[i].push_back(pe * pe);
  std::vector<MapPoint>& map = last_map_[i];
  map.clear();
  for (const auto& l : report.landmarks) {
    all_reported_ += 1.0;
    if (l.moving) moving_reported_ += 1.0;
    if (!l.tentative) map.push_back({l.position_m, l.landmark_id});
  }
  if (!map.empty()) {
    const std::vector<double> errors = LandmarkErrors(map, true_landmarks_, frames_[i]);
    double sq = 0.0;
    for (const double err : errors) sq += err * err;
    frame_rmse_[i].push_back(std::sqrt(sq / static_cast<double>(errors.size())));
  }
  reached_[i].resize(truth.landmarks.size(), 0);
  const Eigen::Vector2d robot_xy = truth.robots[i].pose.Translation();
  for (std::size_t l = 0; l < truth.landmarks.size(); ++l) {
    if ((true_landmarks_[l].position_m - robot_xy).norm() <= lidar_range_m_) reached_[i][l] = 1;
  }
}

PaperBScores PaperBScorer::Finish() const {
  PaperBScores row;
  std::vector<TruePoint> static_landmarks;
  for (std::size_t l = 0; l < true_landmarks_.size(); ++l) {
    if (is_static_[l]) static_landmarks.push_back(true_landmarks_[l]);
  }
  const std::size_t n = frames_.size();
  std::vector<double> static_only_completeness;  // per robot
  for (std::size_t i = 0; i < n; ++i) {
    row.robot_landmark_rmse_m.push_back(MeanOfFinite(frame_rmse_[i]));
    row.robot_rmse_per_robot_m.push_back(std::sqrt(MeanOfFinite(position_sq_[i])));
    const std::vector<int> matched = MatchedTruth(last_map_[i], true_landmarks_, frames_[i]);
    const std::vector<int> matched_static = MatchedTruth(last_map_[i], static_landmarks, frames_[i]);
    int reach = 0, kept = 0, kept_static = 0;
    for (std::size_t l = 0, s = 0; l < true_landmarks_.size(); ++l) {
      if (!is_static_[l]) continue;
      const int static_index = static_cast<int>(s++);
      if (!reached_[i][l]) continue;
      ++reach;
      if (std::binary_search(matched.begin(), matched.end(), static_cast<int>(l))) ++kept;
      if (std::binary_search(matched_static.begin(), matched_static.end(), static_index)) ++kept_static;
    }
    row.robot_completeness.push_back(reach > 0 ? static_cast<double>(kept) / reach : std::nan(""));
    static_only_completeness.push_back(reach > 0 ? static_cast<double>(kept_static) / reach : std::nan(""));
    row.mapped_at_end += static_cast<double>(last_map_[i].size()) / static_cast<double>(n);
  }
  row.landmark_rmse_m = MeanOfFinite(row.robot_landmark_rmse_m);
  row.robot_rmse_m = MeanOfFinite(row.robot_rmse_per_robot_m);
  row.static_completeness = MeanOfFinite(row.robot_completeness);
  row.static_only_completeness = MeanOfFinite(static_only_completeness);
  row.moving_flag_share = all_reported_ > 0.0 ? moving_reported_ / all_reported_ : 0.0;
  return row;
}

}  // namespace mrslam::evaluator
