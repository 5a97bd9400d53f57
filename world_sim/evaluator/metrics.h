#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"

// The metric functions of docs/metrics.md, in one small library that the evaluator process, the batch
// tools and the tests share. Pure: no DDS. Errors of a robot are measured in its own frame G_i,
// through the true frame pose (truth_in_G_i = inverse(frame_in_world) * truth_in_world).
namespace mrslam::evaluator {

// A landmark of a robot's map at one step, in the robot's frame.
struct MapPoint {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int landmark_id = -1;  // reported identity, -1 if unknown
  // Its position covariance as the map reports it (zero when unknown), and the robot (scenario
  // index) that first mapped it, -1 if unknown (a landmark taken from a peer names the peer).
  Eigen::Matrix2d covariance_m2 = Eigen::Matrix2d::Zero();
  int origin_robot = -1;
};

// A true landmark at one step, in the world frame.
struct TruePoint {
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
  int landmark_id = 0;
};

// The truth expressed in a robot's own frame G_i:
//   T(G_i <- body) = T(W <- G_i)^-1 * T(W <- body).
common::Pose2 TruthInOwnFrame(const common::Pose2& truth_in_world, const common::Pose2& frame_in_world);

// Position error (m), ||t_est - t_true||, and absolute wrapped heading error (rad),
// |wrap(phi_est - phi_true)| in [0, pi], of an estimate in G_i.
double PositionError(const common::Pose2& estimate, const common::Pose2& truth_in_own_frame);
double HeadingError(const common::Pose2& estimate, const common::Pose2& truth_in_own_frame);

// Normalized estimation error squared of a pose estimate (3 dof):
//   e = (x_est - x, y_est - y, wrap(phi_est - phi)),  NEES = e^T P^-1 e.
// Its expectation is 3 for a consistent filter. NaN if P is not positive definite.
double PoseNees(const common::Pose2& estimate, const Eigen::Matrix3d& covariance,
                const common::Pose2& truth_in_own_frame);

// Per map landmark, its error (m) against the true current position of the landmark it stands
// for: by reported identity when it has one (and a true landmark with that id exists), else by
// an optimal assignment among the true landmarks not claimed by identity, with a cut-off: a map
// landmark with no true partner within cutoff_m counts as cutoff_m. Returns one error per map
// landmark, in map order; every error is in [0, cutoff_m].
//
// The assignment minimizes sum_k min(d_k^2, cutoff_m^2), the total squared distance with pairs
// beyond the cut-off costing the same as no partner (as in OSPA), so a far ghost cannot pull a
// true landmark away from a map landmark that is near it.
std::vector<double> LandmarkErrors(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                                   const common::Pose2& frame_in_world, double cutoff_m = 3.0);

// The true landmark (index into truth, or -1 beyond the cut-off) that a map landmark stands for,
// and its error (cutoff_m without a partner), as LandmarkErrors matches them.
struct LandmarkMatch {
  int truth_index = -1;
  double error_m = 0.0;
};
// One match per map landmark, in map order (the rules of LandmarkErrors).
std::vector<LandmarkMatch> MatchLandmarks(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                                          const common::Pose2& frame_in_world, double cutoff_m = 3.0);

// Indices of the true landmarks (into truth) that some map landmark stands for (as matched by
// LandmarkErrors within the cut-off), ascending, each once.
std::vector<int> MatchedTruth(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                              const common::Pose2& frame_in_world, double cutoff_m = 3.0);

// How two robots' maps agree on the true landmarks both hold (by true id, the map landmark
// standing for each, in each robot's own frame): of the landmarks both hold with a positive
// definite covariance, how many there are and how many the two place within sd standard
// deviations of each other, d^T (C_a' + C_b')^-1 d <= sd^2 with d the difference of the two
// positions in the world frame (through the robots' true frames) and C' their covariances
// rotated into it.
struct MapAgreement {
  int common = 0;
  int within = 0;
};
MapAgreement AgreementOfMaps(const std::map<int, MapPoint>& a, const common::Pose2& frame_a,
                             const std::map<int, MapPoint>& b, const common::Pose2& frame_b, double sd = 3.0);

// Minimum-cost assignment (Hungarian algorithm, O(n^2 m) with potentials) of rows to columns of
// a cost matrix (rows <= columns or not): returns for each row the assigned column or -1. Every
// row gets a column when rows <= columns, else every column gets a row; the total cost of the
// assigned pairs is the minimum over all such assignments. Costs must be finite.
std::vector<int> OptimalAssignment(const Eigen::MatrixXd& cost);

// Root mean square of a set of values (0 for none).
double Rmse(const std::vector<double>& errors);

// The root mean square of errors added one at a time, without keeping them: equal to Rmse of
// the same errors in the same order, bit for bit.
class RunningRmse {
 public:
  void Add(double error) {
    sum_sq_ += error * error;
    ++count_;
  }
  double Value() const;
  std::size_t count() const { return count_; }

 private:
  double sum_sq_ = 0.0;
  std::size_t count_ = 0;
};
// Median and p-th percentile (p in [0, 100], linear interpolation between the closest ranks as
// numpy's default: rank r = p / 100 * (n - 1)); NaN for no values.
double Median(std::vector<double> values);
double Percentile(std::vector<double> values, double p);

// Error of an estimated frame transform T(G_i <- G_j) against the truth, translation in G_i.
struct TransformError {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};
// True T(G_i <- G_j) = T(W <- G_i)^-1 * T(W <- G_j); translation_m = ||t_est - t_true|| (in G_i),
// rotation_rad = |wrap(phi_est - phi_true)|.
TransformError FrameTransformError(const common::Pose2& t_i_j_estimate, const common::Pose2& frame_i_in_world,
                                   const common::Pose2& frame_j_in_world);

}  // namespace mrslam::evaluator
