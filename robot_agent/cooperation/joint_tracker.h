#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/archive.h"
#include "common/se2.h"
#include "robot_agent/cooperation/factor_exchange.h"
#include "robot_agent/cooperation/joint_chains.h"
#include "robot_agent/cooperation/joint_estimate.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/joint_graph.h"

// The joint estimate kept as a run goes (docs/cooperation.md, "What the steps are used for").
namespace mrslam::robot_agent::cooperation {

// With raw measurements shared (JointTracker::Enabled), two ways by the landmarks' kinematics:
// * Taken as static: every cooperation.joint_every_s of run time (0: never; at the steps that
//   are multiples of it, the same for every agent), if steps of other robots are held and new
//   ones arrived since the last solve, the joint graph over everything held is solved again,
//   warm-started from the last one (JointGraph::WarmStart; a few iterations, not to
//   convergence).
// * Known candidates (moving landmarks of known kinematics): after every step, the joint
//   estimate with every landmark's path (JointChains), as long as a peer's data are held.
// The own estimate is then the filter's moved by the rigid motion C = J_s * F_s^-1 that takes
// the filter's pose F_s of the step s of the last solve to the joint estimate's J_s: pose
// C * F_k, landmarks C * p, covariances rotated by C's heading. Among static landmarks the
// filter's uncertainty is kept (the joint estimate's own is smaller, so this errs on the large
// side); among movers the pose covariance of a step solved is the joint estimate's marginal, and
// a joint pose beyond the filter's uncertainty is not taken (the filter's estimate stands). At
// the end, Final gives the joint estimate over everything held (the static graph solved once
// more from the last one, to convergence). Pure; not thread-safe.
class JointTracker {
 public:
  explicit JointTracker(const AgentOptions& options);
  static bool Enabled(const AgentOptions& options);

  // After step k, the own step held in `logs` (FactorExchange::logs, after Cooperation::AfterStep)
  // and `estimate` the filter's of step k: solves when due. steps_received: the steps of other
  // robots taken in so far (FactorExchange::steps_received), to see whether new ones arrived.
  // Among moving landmarks also the peers' track links and the frames held
  // (Cooperation::track_links, known_transforms).
  void AfterStep(std::uint32_t k, const filters::FilterEstimate& estimate, const std::map<std::string, FactorLog>& logs,
                 std::uint64_t steps_received, const PeerTrackLinks& links = {},
                 const std::vector<FrameTransform>& frames = {});
  // The filter's estimate in the joint estimate's place (unchanged before the first solve).
  filters::FilterEstimate Corrected(filters::FilterEstimate estimate) const;
  // The joint estimate over everything held, warm-started from the last graph.
  JointEstimate Final(const std::map<std::string, FactorLog>& logs);

  const common::Pose2& correction() const { return correction_; }
  int solves() const { return solves_; }

  // The correction and the schedule, and what the joint estimate among movers learnt; the graph
  // is not written (after a restore the next solve starts cold).
  void Io(common::Archive& ar) {
    ar(correction_, pose_covariance_, next_due_, received_at_solve_, solves_);
    chains_.Io(ar);
  }

 private:
  JointEstimate Solve(const std::map<std::string, FactorLog>& logs, bool to_convergence);

  AgentOptions options_;
  JointChains chains_;
  std::uint32_t every_steps_ = 0;
  std::unique_ptr<smoother::JointGraph> graph_;  // the last one solved
  common::Pose2 correction_;
  std::optional<Eigen::Matrix3d> pose_covariance_;  // among movers: the joint estimate's, when taken
  std::uint32_t next_due_ = 0;
  std::uint64_t received_at_solve_ = 0;
  int solves_ = 0;
};

}  // namespace mrslam::robot_agent::cooperation
