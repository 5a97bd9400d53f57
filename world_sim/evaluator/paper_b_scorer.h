#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "common/sensor_types.h"
#include "world_sim/evaluator/metrics.h"

namespace mrslam::evaluator {

// A landmark as a filter reports it, with the flags paper B's metrics read.
struct ReportedLandmark {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();  // in the robot's own frame
  int landmark_id = -1;                                  // reported identity, -1 if unknown
  bool tentative = false;                                // not (yet) part of the map
  bool moving = false;                                   // held as moving
};

// What one robot reports at one frame.
struct RobotReport {
  common::Pose2 pose;
  std::vector<ReportedLandmark> landmarks;
};

// One run's figures by paper B's definitions (docs/metrics.md): means over the robots, then per
// robot in scenario order. NaN where a figure has nothing to average.
struct PaperBScores {
  double landmark_rmse_m = 0.0;
  double robot_rmse_m = 0.0;
  double static_completeness = 0.0;
  double static_only_completeness = 0.0;
  std::vector<double> robot_landmark_rmse_m, robot_rmse_per_robot_m, robot_completeness;
  double moving_flag_share = 0.0;  // reported moving landmarks / reported landmarks, over frames
  double mapped_at_end = 0.0;      // landmarks in the map at the end, mean over robots
};

// Mean of the finite values; NaN for none.
double MeanOfFinite(const std::vector<double>& values);

// Paper B's metrics, frame by frame, of every robot of a run: the sibling of RobotScorer for the
// experiment grid, built on the same metric functions. Per robot, in its own frame:
//   landmark RMSE (paper B's eqs. 17-18): at frame k, RMSE_k = sqrt(mean_i |m_i - l_i(k)|^2)
//     over the map's landmarks (the reported ones that are not tentative), each against the true
//     position at k of the landmark it stands for (LandmarkErrors); the mean of RMSE_k over the
//     frames at which the map is not empty;
//   robot RMSE: sqrt(mean_k |p_est(k) - p_true(k)|^2);
//   static completeness: of the static true landmarks that came within the lidar's range of the
//     robot at some frame, the share that stands in its map at the end (MatchedTruth);
//   static-only completeness: the same with the map's points assigned among the static true
//     landmarks only, so that a mover passing a static landmark's map point cannot take it.
class PaperBScorer {
 public:
  // frames_in_world: each robot's own frame G_i, in scenario order.
  PaperBScorer(std::vector<common::Pose2> frames_in_world, double lidar_range_m);

  // One frame: the truth and each robot's report, in scenario order.
  void AddFrame(const common::GroundTruth& truth, const std::vector<RobotReport>& reports);
  PaperBScores Finish() const;

 private:
  void AddRobot(std::size_t i, const common::GroundTruth& truth, const RobotReport& report);

  std::vector<common::Pose2> frames_;
  double lidar_range_m_;
  std::vector<std::vector<double>> frame_rmse_, position_sq_;
  std::vector<std::vector<std::uint8_t>> reached_;
  std::vector<std::vector<MapPoint>> last_map_;
  double moving_reported_ = 0.0, all_reported_ = 0.0;
  std::vector<TruePoint> true_landmarks_;
  std::vector<bool> is_static_;
};

}  // namespace mrslam::evaluator
