#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

// Merging a peer's map into an agent's own: a peer landmark moved into the own frame with the
// transform's uncertainty, matching peer landmarks to own ones, and the fusion rules.
namespace mrslam::robot_agent::filters {

// A peer landmark (in G_peer) expressed in G_self through T(G_self <- G_peer):
//   (p', heading') = Compose(T, (p, heading)),
//   P' = J_T C_T J_T^T + J_L P J_L^T,  J_T = ComposeJacobianLeft(T, L), J_L = ComposeJacobianRight(T, L)
// (the transform's error and the landmark's error taken as independent). Speed and turn rate
// are body quantities and do not change.
MapLandmark TransformLandmark(const MapLandmark& in_peer, const common::Pose2& t_self_peer,
                              const Eigen::Matrix3d& t_covariance);

// Fuses a second estimate z (covariance r) of the first m = z.size() components of the state
// (x, p) into it, by rule. With H = [I_m 0] the three rules are one gain form
//   x += K (z - H x),  P = (I - K H) P0 (I - K H)^T + K R0 K^T:
//  - weighted (information fusion, optimal for independent estimates): P0 = P, R0 = r,
//    K = P H^T (H P H^T + r)^-1;
//  - covariance intersection: P0 = P / omega, R0 = r / (1 - omega), K as above with P0, R0,
//    omega in (0, 1) minimizing det(P). Equivalent to P^-1 = omega P^-1 + (1 - omega) H^T r^-1 H.
//    Consistent whatever the (unknown) correlation between the two estimates;
//  - average (paper A): K = [I_m / 2; 0], the plain mean of the observed components; P is the
//    covariance of that mean for independent inputs.
// angle_index (< m) names a component whose difference is wrapped to (-pi, pi] (then re-wrapped
// in x); -1 for none. Returns false (state unchanged) when the covariances are not usable.
bool FuseObservation(Eigen::VectorXd* x, Eigen::MatrixXd* p, const Eigen::VectorXd& z, const Eigen::MatrixXd& r,
                     MapFusionRule rule, int angle_index = -1);

// A landmark position to match, with its covariance and reported identity (-1 if none).
struct MatchCandidate {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  int landmark_id = -1;
  std::int64_t origin = -1;  // OriginKey of its provenance, -1 if unknown
  bool stationary = false;   // taken as static (kTooClose applies to static landmarks only)
};

// One number for a provenance (robot index, track id); -1 when the robot is unknown (< 0).
std::int64_t OriginKey(int origin_robot, std::uint32_t origin_track);

// Matches incoming landmarks to own ones, one to one: when both carry reported identities they
// match exactly when the identities are equal; landmarks of the same provenance (equal origin
// keys) match as identities do; otherwise a pair is a candidate when the squared Mahalanobis
// distance of the positions under the sum of their covariances is within gate_d2 (chi-square,
// 2 dof). Candidates are taken greedily by increasing distance (identity and provenance matches
// first). Returns, per incoming landmark, the index of its own match, or kTooClose for an
// unmatched stationary one (without a reported identity) that lies within too_close_m
// (Euclidean) of a stationary own landmark, or -1. Static landmarks stand apart as the world
// places them; moving ones may pass close by others, so there nearness says nothing.
constexpr int kTooClose = -2;
std::vector<int> MatchLandmarks(const std::vector<MatchCandidate>& own, const std::vector<MatchCandidate>& incoming,
                                double gate_d2, double too_close_m = 0.0);

}  // namespace mrslam::robot_agent::filters
