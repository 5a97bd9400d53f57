#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/cooperation/factor_exchange.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/cooperation/reach_grid.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/mover_memory.h"

namespace mrslam::robot_agent::cooperation {

// Peers' landmarks as their origins estimate them, streamed with their raw measurements
// (TrackEstimate, docs/cooperation.md "Peers' landmarks streamed"), shown in the map an agent
// publishes where its own map holds nothing for them. They take no part in any estimate: the
// filter and the joint graph never see them, so nothing is counted twice and a peer's error
// cannot move the robot. Each origin's newest estimate of each of its labels is placed in the own
// frame through the transform held to that origin (TransformLandmark: the transform's covariance
// added); a moving one is predicted from its estimate's time to now as the online smoother
// predicts its own movers out of sight (smoother::MoverMemory::Predict; movers are shown only
// among landmarks of estimated motion, filter.landmark_kinematics constant_turn_rate with
// filter.smoother.mover_memory_s > 0). Where the robot's own lidar has reached, its own map
// stands: a placed landmark is not shown when a cell (kCellM) within kReachSds sd of its position
// has been within the lidar's reach from the robot's pose (widened by kReachSds sd of the pose's
// position), nor when that sd is wider than the lidar's range (it says nothing the robot could
// check). A static landmark a peer maps where the robot has looked and the robot lacks is most
// likely one that moves; a landmark the robot has had in reach is better shown as it saw it. Of
// the rest, newest estimates first, one is shown unless the map already holds one of the same
// identity or provenance, or one within cooperation.merge_min_separation_m (landmarks stand
// apart as the world places them; a covariance gate would not tell, as the transform's
// uncertainty is common to all of an origin's landmarks).
class StreamedLandmarks {
 public:
  // The track ids of the landmarks shown: kFirstTrack | (origin's team index << 20) | label
  // (labels at most kMaxTrackLabel, 20 bits).
  static constexpr std::uint32_t kFirstTrack = 0xC0000000U;
  static constexpr double kCellM = 0.5;
  static constexpr double kReachSds = 3.0;

  explicit StreamedLandmarks(const AgentOptions& options);

  // Marks where the lidar reaches from the pose of estimate (nothing for a pose or covariance
  // not finite).
  void Observe(const filters::FilterEstimate& estimate);
  // Appends to the map of estimate the landmarks placed from logs through transforms that are
  // shown (the rules above).
  void Append(const std::map<std::string, FactorLog>& logs, const std::vector<FrameTransform>& transforms,
              filters::FilterEstimate* estimate) const;

  void Io(common::Archive& ar) { reached_.Io(ar); }
  std::size_t Bytes() const { return reached_.Bytes(); }

 private:
  struct Placed {
    std::uint32_t step = 0;  // of the origin's estimate
    filters::MapLandmark landmark;
  };

  // Every origin's newest estimates (but the own) placed in the own frame at time_s and not
  // where the robot has reached, newest first.
  std::vector<Placed> Place(const std::map<std::string, FactorLog>& logs, const std::vector<FrameTransform>& transforms,
                            double time_s) const;
  std::optional<filters::MapLandmark> Placement(const std::string& origin, const FactorLog& log, const TrackEstimate& t,
                                                const FrameTransform& frame, double time_s) const;
  // Whether a cell within kReachSds sd of l's position has been within reach (any, when that is
  // wider than the lidar's range).
  bool Reached(const filters::MapLandmark& l) const;

  AgentOptions options_;
  bool movers_shown_ = false;
  smoother::MoverMemory movers_;
  ReachGrid reached_;  // where the lidar has reached
};

}  // namespace mrslam::robot_agent::cooperation
