#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/angles.h"
#include "common/rng.h"
#include "common/se2.h"

// Pose errors, their NEES and Gaussian pose samples, for the cooperation tests.
namespace mrslam::robot_agent::cooperation {

using common::Pose2;

inline Eigen::Vector3d PoseError(const Pose2& estimate, const Pose2& truth) {
  return {estimate.x - truth.x, estimate.y - truth.y, common::WrapAngle(estimate.heading - truth.heading)};
}

inline double Nees(const Pose2& estimate, const Pose2& truth, const Eigen::Matrix3d& cov) {
  const Eigen::Vector3d e = PoseError(estimate, truth);
  return e.dot(cov.ldlt().solve(e));
}

inline Pose2 SamplePose(common::Rng* rng, const Pose2& mean, const Eigen::Matrix3d& cov) {
  const Eigen::LLT<Eigen::Matrix3d> llt(cov);
  const Eigen::Vector3d n(rng->Normal(), rng->Normal(), rng->Normal());
  return Pose2::FromVector(mean.Vector() + llt.matrixL() * n);
}

}  // namespace mrslam::robot_agent::cooperation
