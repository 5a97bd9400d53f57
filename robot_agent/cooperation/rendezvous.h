#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "common/se2.h"

// The maths of a rendezvous (docs/design.md "Frames", docs/cooperation.md; Zhou & Roumeliotis 2006): the
// transform between two robots' frames from their mutual range-bearing detections and their
// pose estimates, with its covariance; the composition of transforms (chaining through a peer);
// the fusion of repeated estimates of one transform; and its refinement by the landmarks both
// robots' maps hold.
namespace mrslam::robot_agent::cooperation {

// One mutual detection: robot i saw robot j at (range_ij, bearing_ij) and robot j saw robot i
// at (range_ji, bearing_ji); bearings relative to the observer's heading.
struct MutualDetection {
  double range_ij_m = 0.0;
  double bearing_ij_rad = 0.0;
  double range_ji_m = 0.0;
  double bearing_ji_rad = 0.0;
  bool has_range_ji = true;  // without it rho = range_ij only
};

// An estimate of T(G_a <- G_b) with its covariance over (x, y, heading), split for split
// covariance intersection into a part whose correlation with other estimates is unknown
// (dependent: the robots' pose errors, shared by every estimate made from the same filters) and
// a part independent of every other estimate (the measurement noise of this detection):
//   covariance = dependent + independent.
struct TransformEstimate {
  common::Pose2 t;
  Eigen::Matrix3d dependent = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d independent = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d Covariance() const { return dependent + independent; }

  void Io(common::Archive& ar) { ar(t, dependent, independent); }
};

// Robot j's pose in robot i's body frame from a mutual detection (docs/cooperation.md):
//   rho = (range_ij + range_ji) / 2,
//   T(R_i <- R_j) = (rho cos b_ij, rho sin b_ij, pi + b_ij - b_ji),
// and its Jacobian with respect to z = (range_ij, bearing_ij, range_ji, bearing_ji):
//   d(x, y)/d range_ij = d(x, y)/d range_ji = (cos b_ij, sin b_ij) / 2,
//   d(x, y)/d b_ij = rho (-sin b_ij, cos b_ij),  d heading/d b_ij = 1, d heading/d b_ji = -1.
// Swapping the roles of i and j gives exactly the inverse pose.
common::Pose2 RelativePoseFromMutual(const MutualDetection& z, Eigen::Matrix<double, 3, 4>* jacobian);

// Jacobian of Inverse(a_b) with respect to a_b: inverse = (-c x - s y, s x - c y, -h).
Eigen::Matrix3d InverseJacobian(const common::Pose2& a_b);

// T(G_i <- G_j) = T(G_i <- R_i) * T(R_i <- R_j) * inverse(T(G_j <- R_j)), by first-order
// propagation of the pose covariances of both robots (each in its own frame, independent of
// each other) and the measurement noise (var_range, var_bearing per reading):
//   C = J_i P_i J_i^T + J_j P_j J_j^T  (dependent: the filters' errors)
//     + J_z R J_z^T                    (independent: this detection's noise),
//   J_i = ComposeJacobianLeft(pose_i, rel * inv(pose_j)),
//   J_z = ComposeJacobianRight(pose_i, rel * inv(pose_j)) * ComposeJacobianLeft(rel, inv(pose_j)) * J_rel,
//   J_j = ComposeJacobianRight(pose_i * rel, inv(pose_j)) * InverseJacobian(pose_j).
TransformEstimate TransformFromMutual(const common::Pose2& pose_i, const Eigen::Matrix3d& cov_i,
                                      const common::Pose2& pose_j, const Eigen::Matrix3d& cov_j,
                                      const MutualDetection& z, double var_range, double var_bearing);

// T(A <- C) = T(A <- B) * T(B <- C) with the first-order covariance
//   J_l C_ab J_l^T + J_r C_bc J_r^T (the two taken as independent); the result is all dependent.
TransformEstimate ChainTransforms(const TransformEstimate& a_b, const TransformEstimate& b_c);

// The inverse estimate T(B <- A), covariance J C J^T per part.
TransformEstimate InvertTransform(const TransformEstimate& a_b);

// Squared Mahalanobis distance between two estimates of one transform under the sum of their
// covariances (heading difference wrapped); infinity when that sum is singular.
double TransformDistanceSquared(const TransformEstimate& a, const TransformEstimate& b);

// Chi-square quantile for 3 degrees of freedom (bisection on the CDF
// F(x) = erf(sqrt(x / 2)) - sqrt(2 x / pi) exp(-x / 2)).
double ChiSquare3Quantile(double p);

// Split covariance intersection (Julier & Uhlmann 2001; Li et al. 2013) of two estimates of one
// transform whose dependent parts have unknown correlation and whose independent parts are
// independent. For omega in [0, 1]:
//   P_a' = D_a / omega + I_a,  P_b' = D_b / (1 - omega) + I_b,
//   P = (P_a'^-1 + P_b'^-1)^-1,  x = P (P_a'^-1 x_a + P_b'^-1 x_b)  (x_b's heading unwrapped
//   next to x_a's),
//   independent part I = P (P_a'^-1 I_a P_a'^-1 + P_b'^-1 I_b P_b'^-1) P, dependent D = P - I,
// with omega minimizing det(P) (golden-section search). It is consistent for any correlation of
// the dependent parts, and when both are zero it is the information (Kalman) fusion.
TransformEstimate FuseSplitCi(const TransformEstimate& a, const TransformEstimate& b);

// One landmark as two maps hold it: pose (x, y, heading) and covariance in G_a (the own map)
// and in G_b (the peer's map), at the same step. use_heading: both maps know its heading (a
// moving landmark's direction of travel); otherwise only the position constrains the alignment.
struct LandmarkPair {
  Eigen::Vector3d in_a = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance_a = Eigen::Matrix3d::Identity();
  Eigen::Vector3d in_b = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance_b = Eigen::Matrix3d::Identity();
  bool use_heading = false;
};

// Refines an estimate of T = T(G_a <- G_b) by the landmarks both maps hold: a weighted
// least-squares 2-D rigid alignment, solved by Gauss-Newton over (x, y, heading), with the
// held estimate as a prior factor. Landmark n gives the residual
//   r_n = l_a - T * l_b  (position; and heading, wrapped, when use_heading),
//   S_n = P_a + J_r P_b J_r^T,  J_r = ComposeJacobianRight(T, l_b),  d r_n / d T = -ComposeJacobianLeft(T, l_b).
// The factors are not independent: every landmark of one map carries that robot's pose error,
// the same error that makes the prior (its dependent part), so the combination is a split
// covariance intersection in information form. For omega in [0, 1]:
//   Lambda(omega) = (D / omega + I)^-1 + (1 - omega) / N * sum_n J_n^T S_n^-1 J_n,
// the landmark factors taken with equal weights 1 / N (covariance intersection among N
// estimates of unknown correlation) and all together with 1 - omega against the prior's
// dependent part D (its independent part I, the measurement noise, stays independent);
// T(omega) minimizes the matching weighted sum of squares and P = Lambda^-1 at T(omega);
// omega minimizes det(P). Consistent whatever the correlations; with one pair and no heading
// the landmarks alone do not fix T and the prior fills the gap. The independent part of the
// result is P (D / omega + I)^-1 I (D / omega + I)^-1 P, the rest is dependent. Swapping a and b
// in every pair and inverting the prior gives the inverse result (the landmark residuals are the
// same up to a rotation; the prior up to linearization). Returns nullopt when pairs is empty or
// Gauss-Newton fails.
std::optional<TransformEstimate> AlignLandmarks(const TransformEstimate& prior, const std::vector<LandmarkPair>& pairs);

}  // namespace mrslam::robot_agent::cooperation
