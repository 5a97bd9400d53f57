#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/cooperation/factor_exchange.h"
#include "robot_agent/cooperation/joint_estimate.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/batch_smoother.h"

// The joint estimate among landmarks of known kinematics (docs/cooperation.md, "Among moving
// landmarks"): the MAP estimate of the own path, the paths of the peers whose data the agent
// holds and every labelled landmark's path (a state per step, BatchSmoother) from the raw
// measurements held.
namespace mrslam::robot_agent::cooperation {

// The kinematics the joint estimate gives a mapped landmark: kStaticKinematics, or the index of
// the known candidate nearest its (v, w); nothing for a landmark whose heading is not known yet
// or that is tracked with a constant turn rate.
constexpr int kStaticKinematics = -1;
std::optional<int> TrackKinematics(const FilterOptions& filter, const filters::MapLandmark& l);
smoother::BatchSmoother::Kinematics KinematicsOf(const FilterOptions& filter, int index);

// A track's kinematics `now` (TrackKinematics), or the candidate it was last seen to follow
// (seen_moving, if any) when it is now taken as static or not known: a filter may take a mover
// seen from far as static for a while.
std::optional<int> KeptKinematics(std::optional<int> seen_moving, std::optional<int> now);

// Whether an agent keeps the joint estimate among movers (JointChains): raw measurements shared
// among landmarks of known kinematics.
bool JointAmongMovers(const AgentOptions& options);

// A peer's track as the own agent knows it from the peer's map snapshots: the own track it was
// matched to (0: none) and its kinematics (TrackKinematics of the peer's landmark).
struct TrackLink {
  std::uint32_t own_track = 0;
  int kinematics = kStaticKinematics;

  void Io(common::Archive& ar) { ar(own_track, kinematics); }
};
using PeerTrackLinks = std::map<std::string, std::map<int, TrackLink>>;  // peer -> its track -> link

// The step with each landmark reading relabelled by `labels` (those without a label left out).
common::SensorStep Relabelled(const common::SensorStep& step, const std::map<int, int>& labels);

// Solved again after every step. The problem: the own robot (its first pose known) and every
// peer whose log is held, whose frame is known and of whose tracks at least one is matched to an
// own one (its first pose an unknown, started from the held transform); the readings labelled
// by the own tracks, a peer's by the own track its track was matched to or else by a label of
// its own (where the sensor reports identities, every robot's by identity, as shared); each label's kinematics the own
// filter's (KeptKinematics), a peer's unmatched track's the peer's; readings of tracks of unknown kinematics and of
// robots outside the problem left out. While the problem's robots, labels and kinematics stay the same, each solve adds
// the steps new since the last one and starts from its solution; when they change it is built again and started from
// the last solution where they share robots and tracks (BatchSmoother::StartFrom); built with nothing to start from
// (the first time, after a restore), it is solved as it grows. Within cooperation.max_history_steps own steps only (the
// cost grows with the steps held). Pure; not thread-safe.
class JointChains {
 public:
  explicit JointChains(const AgentOptions& options);

  // After step k, `own` the filter's estimate of step k and the own log held to k: the own pose
  // of step k in the joint estimate and its covariance, or nothing (no peer in the problem, the own log not held to
  // k, or past max_history_steps).
  struct OwnPose {
    common::Pose2 pose;
    Eigen::Matrix3d covariance;  // its marginal (the Laplace approximation at the solution)
  };
  std::optional<OwnPose> Update(std::uint32_t k, const filters::FilterEstimate& own,
                                const std::map<std::string, FactorLog>& logs, const PeerTrackLinks& links,
                                const std::vector<FrameTransform>& frames);
  // The last solution: the own path (every step) and the peers' frames (empty before a solve).
  JointEstimate Summary() const;

  // What it learnt (the candidates tracks were seen to follow, the correspondences); the problem
  // is not written (after a restore it is built again, solved as it grows).
  void Io(common::Archive& ar) { ar(seen_moving_, learned_); }

 private:
  struct Problem {
    std::vector<std::string> robots;                   // the own first
    std::map<std::string, std::map<int, int>> labels;  // per robot: its track -> label
    std::map<int, int> kinematics;                     // label -> TrackKinematics
    bool operator==(const Problem& o) const {
      return robots == o.robots && labels == o.labels && kinematics == o.kinematics;
    }
  };
  Problem Pose(const filters::FilterEstimate& own, const std::map<std::string, FactorLog>& logs,
               const PeerTrackLinks& links, const std::vector<FrameTransform>& frames) const;
  // The labels of `now` that name the same track as a label of `before` (the own robot's first).
  static std::map<int, int> SameLandmarks(const Problem& before, const Problem& now);
  void Build(const std::map<std::string, FactorLog>& logs, const std::vector<FrameTransform>& frames);
  // Adds the steps held beyond those added, in time order; `cold`: solving as they grow.
  void AddNew(const std::map<std::string, FactorLog>& logs, bool cold);

  // The label of an own landmark: its identity + 1 where the sensor reports identities (the
  // shared logs are labelled so), else its track; 0: none.
  int OwnLabel(const filters::MapLandmark& l) const;
  static constexpr std::uint32_t kMaxOwnLabel = 1U << 30;
  // Keeps the candidate each own track follows while the filter sees it move.
  void Remember(const filters::FilterEstimate& own);
  // The candidate the own label was last seen to follow, if any.
  std::optional<int> SeenMoving(int label) const;
  // Links a peer's track that no snapshot matched to the own track of the same kinematics whose
  // path the solution puts within cooperation.match_gate_probability of its path, when only one
  // is and no other track of that peer stands on it (taken from the next step on).
  void Learn(const filters::FilterEstimate& own);

  AgentOptions options_;
  std::map<int, int> seen_moving_;  // own label -> the candidate it was last seen to follow
  std::map<std::pair<std::string, int>, std::uint32_t> learned_;  // (peer, its track) -> own track
  Problem problem_;
  std::unique_ptr<smoother::BatchSmoother> smoother_;
  std::vector<std::uint32_t> added_;        // per robot of the problem: its steps added
  std::vector<common::Pose2> first_poses_;  // per robot: in its own frame
};

}  // namespace mrslam::robot_agent::cooperation
