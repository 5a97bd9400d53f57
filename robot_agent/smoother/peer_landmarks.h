#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "common/se2.h"
#include "common/sensor_options.h"
#include "common/sensor_types.h"
#include "robot_agent/filters/map_fusion.h"
#include "robot_agent/filters/slam_filter.h"

namespace mrslam::robot_agent::smoother {

// Peers' static landmarks shown beside the online smoother's own map (docs/smoother.md, "Peers'
// maps"). They take no part in its estimate: the front end does not associate the robot's
// readings with them and the graph holds none of them, so a peer's error (its map, or the frame
// transform it came through) cannot move the robot's pose or its own landmarks, and nothing is
// counted twice. They complete the map it publishes where its own has nothing: a held landmark is
// shown while no own landmark matches it, and once one does, the own estimate stands for it.
// A held landmark well inside the robot's own view that no reading of a step explains is missed;
// missed in MissesToDrop steps in a row, it is let go (a peer's map may hold a landmark where a
// moving one once stood, or a ghost).
class PeerLandmarks {
 public:
  // Track ids of the landmarks held here (the own tracks count up from 1 and stay below it).
  static constexpr std::uint32_t kFirstTrack = 0x80000000U;

  // Takes in a peer's landmarks given in the own frame: the static ones (not moving, confirmed,
  // with a positive definite position covariance) that do not lie where the robot has looked:
  // well inside its view (WellInView) from MissesToDrop or more of the poses looked_from (there
  // its own map stands; a static landmark it lacks there is most likely one that moves). One
  // matching a held landmark (filters::MatchLandmarks: identity, provenance, else the chi-square
  // gate gate_d2) replaces it, keeping its track id; the others are added, unless within
  // too_close_m of a held one. Returns how many were added.
  int Merge(const std::vector<filters::MapLandmark>& in, const std::vector<common::Pose2>& looked_from,
            const common::LidarOptions& lidar, double gate_d2, double too_close_m);
  // Appends to map the held landmarks that match none of its own (same rule).
  void AppendUnmatched(std::vector<filters::MapLandmark>* map, double gate_d2, double too_close_m) const;
  // Counts the misses of one step's scan (readings: those that may explain a static landmark)
  // taken at pose (position covariance pose_xy, heading variance heading_var): a held landmark
  // that LookFor finds missed counts one more miss in a row, one it finds explained none.
  void CountMisses(const common::Pose2& pose, const Eigen::Matrix2d& pose_xy, double heading_var,
                   const std::vector<common::LandmarkDetection>& readings, const common::LidarOptions& lidar,
                   double gate_d2);
  // The misses in a row that let a landmark go: the fewest k >= 2 with (1 - p)^k <= 1e-3 for the
  // lidar's detection probability p (a landmark that is there is let go by chance at most once
  // in a thousand such runs).
  static int MissesToDrop(double detection_probability);

  std::size_t size() const { return held_.size(); }
  // sizeof(element) * size() of what it holds.
  std::size_t Bytes() const { return held_.size() * sizeof(Held); }
  void Io(common::Archive& ar) { ar(held_, next_track_); }

 private:
  struct Held {
    filters::MapLandmark landmark;
    int misses = 0;  // steps in a row
    void Io(common::Archive& ar) { ar(landmark, misses); }
  };
  std::vector<filters::MatchCandidate> HeldCandidates() const;

  std::vector<Held> held_;
  std::uint32_t next_track_ = kFirstTrack;
};

// Whether a point at h from the sensor lies well inside its view: within 0.9 of its range (and
// beyond its minimum), within 0.45 of its field of view about the heading.
bool WellInView(const common::RangeBearing& h, const common::LidarOptions& lidar);

// What a scan taken at pose (position covariance pose_xy, heading variance heading_var) says of
// a mapped landmark: out of view unless it lies well inside the view (WellInView); explained when
// a reading at position z has d = z - l with d^T (P_l + pose_xy + s^2 I)^-1 d <= gate_d2,
// s^2 = sd_r^2 + r^2 (sd_b^2 + heading_var) at range r; missed otherwise.
enum class Look { kOutOfView, kExplained, kMissed };
Look LookFor(const filters::MapLandmark& landmark, const common::Pose2& pose, const Eigen::Matrix2d& pose_xy,
             double heading_var, const std::vector<common::LandmarkDetection>& readings,
             const common::LidarOptions& lidar, double gate_d2);

}  // namespace mrslam::robot_agent::smoother
