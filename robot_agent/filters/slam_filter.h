#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/angles.h"
#include "common/archive.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent::filters {

// The variance reported for a landmark heading nothing has shown: that of a uniform angle.
inline constexpr double kUnknownHeadingVar = common::kPi * common::kPi / 3.0;

enum class LandmarkMotionKind : std::uint8_t { kStatic = 0, kUnicycle = 1, kConstantTurnRate = 2 };

// One landmark of an agent's map, in the agent's frame.
struct MapLandmark {
  std::uint32_t track_id = 0;                      // the filter's own identifier
  int landmark_id = -1;                            // reported identity, -1 if unknown
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();  // x_m, y_m, heading_rad
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double v_mps = 0.0;
  double w_radps = 0.0;
  LandmarkMotionKind motion = LandmarkMotionKind::kStatic;
  bool moving = false;
  bool tentative = false;
  std::uint32_t last_seen_step = 0;
  std::uint32_t first_seen_step = 0;  // its first sighting here (merged: the step of the merge)
  // Provenance: the robot (scenario index) that first mapped the landmark and its track id
  // there. Merged landmarks keep theirs, so a landmark coming back from a peer is recognized.
  int origin_robot = -1;
  std::uint32_t origin_track = 0;
};

// A mapped landmark the filter saw move (paper B's ELA test), for "landmark moved" notices.
struct MovedLandmark {
  std::uint32_t step = 0;
  std::uint32_t track_id = 0;
  int landmark_id = -1;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // where it was seen, own frame
};

// What a filter reports after each step.
struct FilterEstimate {
  std::uint32_t step = 0;
  double time_s = 0.0;
  common::Pose2 pose;  // in the agent's own frame
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double effective_sample_size = 1.0;
  int particles = 1;
  std::vector<MapLandmark> landmarks;
  // Whether the filter labels the detections (fastslam; not ekf, ekf_ela), and then per landmark
  // detection of the step's scan, in the scan's order, the track its most probable hypothesis
  // associated it with or created from it (0: none, e.g. ignored or invalid); an identified
  // detection beyond filter.outlier_gate_probability's gate, which the filter leaves out, keeps
  // its landmark's track.
  bool labels_detections = false;
  std::vector<std::uint32_t> detection_tracks;
};

// A SLAM filter for one robot in its own frame: fastslam, ekf or ekf_ela. Pure: no DDS.
class SlamFilter {
 public:
  virtual ~SlamFilter() = default;
  // Predicts with the step's odometry or IMU and corrects with its lidar scan.
  virtual void Process(const common::SensorStep& step) = 0;
  virtual FilterEstimate Estimate() const = 0;
  // Writes or reads back the filter's state: what changes as it runs (estimates, maps, random
  // stream, counters), not what its options fix. A filter made with the same options and seed
  // that reads what another wrote goes on exactly as the writer would have.
  virtual void Io(common::Archive& ar) = 0;
  // The bytes of the state the estimator holds (what grows or not as it runs: particles and
  // their maps, a joint state and its covariance, a graph's keyframes and factors). An estimate,
  // not malloc accounting: the size of the object plus, over its main containers,
  // sizeof(element) * size() (each copy-on-write block shared between particles counted once);
  // caches, scratch buffers, spare capacity, allocator overheads and tree nodes' links are left
  // out.
  virtual std::size_t EstimatorBytes() const = 0;
  // Work whose result serves only the next step (the online smoother's relinearization): a
  // driver with time between steps does it there, after the step's estimate is out; otherwise
  // the next step does it first. The same results either way.
  virtual void Settle() {}

  // Landmarks seen moving since the last call (filters that detect motion: ekf_ela); a filter
  // that tracks moving landmarks instead reports none.
  virtual std::vector<MovedLandmark> TakeMovedLandmarks() { return {}; }
  // A peer's "landmark moved" notice, its position already in the own frame with covariance cov:
  // a filter that keeps only static landmarks removes the mapped landmark it gates to. Returns
  // true if one was removed.
  virtual bool ApplyMovedNotice(const Eigen::Vector2d& /*position*/, const Eigen::Matrix2d& /*cov*/,
                                double /*gate_probability*/) {
    return false;
  }

  // Merges landmarks given in the agent's own frame (a peer's map after the frame transform,
  // predicted to the filter's current step). In every hypothesis (particle), each incoming
  // landmark is gated against the own landmarks (squared Mahalanobis distance of the positions
  // under the sum of their covariances within the chi-square 2 dof quantile of gate_probability;
  // reported identities decide when both carry one); matched landmarks are fused by rule
  // (map_fusion.h), unmatched ones are added, except static ones within too_close_m of a static
  // own landmark (MatchLandmarks' kTooClose), which are left out. Returns how many were added.
  virtual int MergeLandmarks(const std::vector<MapLandmark>& landmarks_in_own_frame, MapFusionRule rule,
                             double gate_probability, double too_close_m) = 0;

  // The final map product of a run: the estimate of the whole path given all the data, (step,
  // pose) in the own frame, from an estimator that smooths; empty for a filter, whose online path
  // is its final trajectory.
  virtual std::vector<std::pair<int, common::Pose2>> FinalTrajectory() const { return {}; }

  // Moves every pose hypothesis to N(pose, covariance), the map kept: the robot was found
  // elsewhere than its motion said. Returns whether the filter supports it (fastslam).
  virtual bool Reseat(const common::Pose2& /*pose*/, const Eigen::Matrix3d& /*covariance*/) { return false; }

  // Cooperative localization: at the current step this robot detected, at (range_m,
  // bearing_rad), a robot whose position in the own frame is N(position, covariance). A filter
  // that supports it weighs its pose hypotheses by that measurement, unless its innovation at
  // the estimate lies beyond the squared Mahalanobis distance gate (an outlier); returns whether
  // it used it.
  virtual bool ObserveKnownRobot(const Eigen::Vector2d& /*position*/, const Eigen::Matrix2d& /*covariance*/,
                                 double /*range_m*/, double /*bearing_rad*/, double /*gate*/) {
    return false;
  }
};

// sizeof(element) * size() of a container: its elements' bytes for EstimatorBytes (tree nodes'
// links, spare capacity and what the elements themselves point to are not counted).
template <typename Container>
std::size_t ElementBytes(const Container& c) {
  return sizeof(typename Container::value_type) * c.size();
}
// The bytes of a FilterEstimate's map and labels (its containers' elements).
std::size_t EstimateBytes(const FilterEstimate& e);

void Io(common::Archive& ar, MapLandmark& l);
void Io(common::Archive& ar, MovedLandmark& m);
void Io(common::Archive& ar, FilterEstimate& e);

// The index of the known kinematics nearest (v, w) (|dv| + |dw|; the first of equals), or -1
// when there are none: which candidate a landmark reported with (v, w) follows.
int NearestKnownKinematics(const std::vector<KnownKinematics>& candidates, double v_mps, double w_radps);

}  // namespace mrslam::robot_agent::filters
