#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"

// The metric functions of DESIGN.md, in one small library that the evaluator process, the batch
// tools and the tests share. Pure: no DDS. Errors of a robot are measured in its own frame G_i,
// through the true frame pose (truth_in_G_i = inverse(frame_in_world) * truth_in_world).
namespace mrslam::evaluator {

// A landmark of a robot's map at one step, in the robot's frame.
struct MapPoint {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int landmark_id = -1;  // reported identity, -1 if unknown
};

// A true landmark at one step, in the world frame.
struct TruePoint {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int landmark_id = 0;
};

// The truth expressed in a robot's own frame.
common::Pose2 TruthInOwnFrame(const common::Pose2& truth_in_world, const common::Pose2& frame_in_world);

// Position error (m) and wrapped heading error (rad) of an estimate in G_i.
double PositionError(const common::Pose2& estimate, const common::Pose2& truth_in_own_frame);
double HeadingError(const common::Pose2& estimate, const common::Pose2& truth_in_own_frame);

// Normalized estimation error squared of a pose estimate (3 dof).
double PoseNees(const common::Pose2& estimate, const Eigen::Matrix3d& covariance,
                const common::Pose2& truth_in_own_frame);

// Per map landmark, its error (m) against the true current position of the landmark it stands
// for: by reported identity when it has one, else by an optimal assignment (minimum total
// squared distance) among the true landmarks not claimed by identity, with a cut-off: a map
// landmark with no true partner within cutoff_m counts as cutoff_m. Returns one error per map
// landmark, in map order.
std::vector<double> LandmarkErrors(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                                   const common::Pose2& frame_in_world, double cutoff_m = 3.0);

// Indices of the true landmarks (into truth) that some map landmark stands for (as matched by
// LandmarkErrors within the cut-off).
std::vector<int> MatchedTruth(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                              const common::Pose2& frame_in_world, double cutoff_m = 3.0);

// Minimum-cost assignment (Hungarian algorithm) of rows to columns of a cost matrix (rows <=
// columns or not): returns for each row the assigned column or -1.
std::vector<int> OptimalAssignment(const Eigen::MatrixXd& cost);

// Root mean square of a set of values (0 for none).
double Rmse(const std::vector<double>& errors);
// Median and p-th percentile (p in [0, 100], linear interpolation); NaN for no values.
double Median(std::vector<double> values);
double Percentile(std::vector<double> values, double p);

// Error of an estimated frame transform T(G_i <- G_j) against the truth, translation in G_i.
struct TransformError {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
TransformError FrameTransformError(const common::Pose2& t_i_j_estimate, const common::Pose2& frame_i_in_world,
                                   const common::Pose2& frame_j_in_world);

}  // namespace mrslam::evaluator
