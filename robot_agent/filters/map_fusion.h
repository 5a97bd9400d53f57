#pragma once

#include <cstdint>
#include <optional>
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

// Fuses a second estimate z (covariance r) of the first M components of the state (x, p) of
// dimension N into it, by rule. With H = [I_M 0] the three rules are one gain form
//   x += K (z - H x),  P = (I - K H) P0 (I - K H)^T + K R0 K^T:
//  - weighted (information fusion, optimal for independent estimates): P0 = P, R0 = r,
//    K = P H^T (H P H^T + r)^-1;
//  - covariance intersection: P0 = P / omega, R0 = r / (1 - omega), K as above with P0, R0,
//    omega in [0, 1] minimizing det(P). Equivalent to P^-1 = omega P^-1 + (1 - omega) H^T r^-1 H.
//    Consistent whatever the (unknown) correlation between the two estimates. omega comes from
//    the M x M blocks alone (CovarianceIntersectionWeight below);
//  - average (paper A): K = [I_M / 2; 0], the plain mean of the observed components; P is the
//    covariance of that mean for independent inputs.
// angle_index (< M) names a component whose difference is wrapped to (-pi, pi] (then re-wrapped
// in x); -1 for none. Returns false (state unchanged) when the covariances are not usable.
// Fixed sizes only: instantiated for (N, M) in {(2, 2), (3, 2), (3, 3), (5, 2), (5, 3)}.
template <int N, int M>
bool FuseObservation(Eigen::Matrix<double, N, 1>* x, Eigen::Matrix<double, N, N>* p,
                     const Eigen::Matrix<double, M, 1>& z, const Eigen::Matrix<double, M, M>& r, MapFusionRule rule,
                     int angle_index = -1);

// The covariance intersection weight of FuseObservation for a state of dimension n whose first
// M components (covariance p_mm) meet an estimate of covariance r. By Sylvester's determinant
// identity, with P(omega)^-1 = omega P^-1 + (1 - omega) H^T r^-1 H,
//   log det P(omega)^-1 = (n - M) log omega + log det(omega r + (1 - omega) p_mm)
//                         - log det r - log det P,
// so with lambda_i the eigenvalues of p_mm relative to r (of L^-1 p_mm L^-T, r = L L^T) the
// weight maximizes the concave
//   g(omega) = (n - M) log omega + sum_i log(lambda_i + omega (1 - lambda_i)).
// Its derivative g'(omega) = (n - M) / omega + sum_i (1 - lambda_i) / (lambda_i + omega (1 - lambda_i))
// decreases; its root in [1e-4, 1 - 1e-4] is found by Newton steps kept inside a bisection
// bracket, to |d omega| <= 1e-12. The end points omega = 1 (keep the own estimate) and, for
// n = M, omega = 0 (take the incoming one) win when their g is larger. nullopt when r or p_mm
// is not positive definite.
template <int M>
std::optional<double> CovarianceIntersectionWeight(const Eigen::Matrix<double, M, M>& p_mm,
                                                   const Eigen::Matrix<double, M, M>& r, int n);

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

// A map landmark as a candidate: its position, identity and provenance; stationary unless moving.
MatchCandidate CandidateOf(const MapLandmark& l);

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
