#include "robot_agent/cooperation/joint_tracker.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "common/angles.h"
#include "common/gaussian.h"
#include "robot_agent/cooperation/rendezvous.h"

namespace mrslam::robot_agent::cooperation {
namespace {

// The rotation of a rigid motion's heading on (x, y), the heading unchanged.
Eigen::Matrix3d Rotation(double heading) {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r.topLeftCorner<2, 2>() << std::cos(heading), -std::sin(heading), std::sin(heading), std::cos(heading);
  return r;
}

}  // namespace

JointTracker::JointTracker(const AgentOptions& options)
    : options_(options),
      chains_(options),
      every_steps_(
          options.cooperation.joint_every_s > 0.0
              ? static_cast<std::uint32_t>(std::max(1.0, std::round(options.cooperation.joint_every_s / options.dt_s)))
              : 0) {
  next_due_ = every_steps_;
}

bool JointTracker::Enabled(const AgentOptions& options) {
  return options.cooperation.share_factors &&
         options.filter.landmark_kinematics != LandmarkKinematics::kConstantTurnRate;
}

JointEstimate JointTracker::Solve(const std::map<std::string, FactorLog>& logs, bool to_convergence) {
  const auto robots = RobotLogs(options_.robot_id, logs);
  auto graph = std::make_unique<smoother::JointGraph>(options_, robots);
  if (graph_) graph->WarmStart(*graph_);
  graph->Solve(to_convergence);
  JointEstimate out = Summarize(*graph, robots);
  graph_ = std::move(graph);
  ++solves_;
  return out;
}

void JointTracker::AfterStep(std::uint32_t k, const filters::FilterEstimate& estimate,
                             const std::map<std::string, FactorLog>& logs, std::uint64_t steps_received,
                             const PeerTrackLinks& links, const std::vector<FrameTransform>& frames) {
  if (JointAmongMovers(options_)) {
    if (const auto joint = chains_.Update(k, estimate, logs, links, frames)) {
      // A joint estimate beyond the filter's own uncertainty is not taken (a wrong match or
      // kinematics among the peers' tracks): the filter's stands.
      const common::Pose2& pose = joint->pose;
      const Eigen::Vector3d d(pose.x - estimate.pose.x, pose.y - estimate.pose.y,
                              common::WrapAngle(pose.heading - estimate.pose.heading));
      const bool within = d.allFinite() && d.dot(estimate.covariance.ldlt().solve(d)) <=
                                               ChiSquare3Quantile(options_.cooperation.transform_gate_probability);
      correction_ = within ? common::Compose(pose, common::Inverse(estimate.pose)) : common::Pose2{};
      pose_covariance_.reset();
      if (within && common::IsSymmetricPositiveDefinite<3>(joint->covariance)) pose_covariance_ = joint->covariance;
      ++solves_;
    } else {
      pose_covariance_.reset();  // the last correction stands, with the filter's uncertainty
    }
    return;
  }
  if (every_steps_ == 0 || k < next_due_) return;
  // Due at the multiples of every_steps_ only, the same steps for every agent: in lockstep the
  // agents' solves then run side by side, not one after the other while the rest wait.
  next_due_ = (k / every_steps_ + 1) * every_steps_;
  if (logs.size() < 2 || steps_received == received_at_solve_) return;
  const auto own = logs.find(options_.robot_id);
  if (own == logs.end() || own->second.Held() != k) return;  // the own log stopped growing
  received_at_solve_ = steps_received;
  const JointEstimate joint = Solve(logs, false);
  if (joint.path.empty() || joint.path.back().first != static_cast<int>(k)) return;
  correction_ = common::Compose(joint.path.back().second, common::Inverse(estimate.pose));
}

filters::FilterEstimate JointTracker::Corrected(filters::FilterEstimate estimate) const {
  if (solves_ == 0) return estimate;
  const Eigen::Matrix3d r = Rotation(correction_.heading);
  estimate.pose = common::Compose(correction_, estimate.pose);
  estimate.covariance = pose_covariance_ ? *pose_covariance_ : Eigen::Matrix3d(r * estimate.covariance * r.transpose());
  for (auto& l : estimate.landmarks) {
    const common::Pose2 p = common::Compose(correction_, common::Pose2::FromVector(l.mean));
    l.mean = p.Vector();
    l.covariance = r * l.covariance * r.transpose();
  }
  return estimate;
}

JointEstimate JointTracker::Final(const std::map<std::string, FactorLog>& logs) {
  return JointAmongMovers(options_) ? chains_.Summary() : Solve(logs, true);
}

}  // namespace mrslam::robot_agent::cooperation
