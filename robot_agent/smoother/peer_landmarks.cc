#include "robot_agent/smoother/peer_landmarks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "common/gaussian.h"

namespace mrslam::robot_agent::smoother {

namespace {

std::vector<filters::MatchCandidate> Candidates(const std::vector<filters::MapLandmark>& landmarks) {
  std::vector<filters::MatchCandidate> out;
  out.reserve(landmarks.size());
  for (const auto& l : landmarks) out.push_back(filters::CandidateOf(l));
  return out;
}

bool Usable(const filters::MapLandmark& l) {
  return !l.moving && !l.tentative && l.mean.head<2>().allFinite() &&
         common::IsSymmetricPositiveDefinite<2>(l.covariance.topLeftCorner<2, 2>());
}

}  // namespace

bool WellInView(const common::RangeBearing& h, const common::LidarOptions& lidar) {
  return h.range_m < 0.9 * lidar.max_range_m && h.range_m > lidar.min_range_m &&
         std::abs(h.bearing_rad) < 0.45 * lidar.fov_rad;
}

int PeerLandmarks::Merge(const std::vector<filters::MapLandmark>& in, const std::vector<common::Pose2>& looked_from,
                         const common::LidarOptions& lidar, double gate_d2, double too_close_m) {
  const int looks_enough = MissesToDrop(lidar.detection_probability);
  const auto looked_at = [&](const filters::MapLandmark& l) {
    int looks = 0;
    for (const common::Pose2& x : looked_from) {
      looks += WellInView(common::MeasureRangeBearing(x, l.mean.head<2>()), lidar) ? 1 : 0;
      if (looks >= looks_enough) return true;
    }
    return false;
  };
  std::vector<filters::MapLandmark> usable;
  for (const auto& l : in) {
    if (Usable(l) && !looked_at(l)) usable.push_back(l);
  }
  const std::vector<int> match = filters::MatchLandmarks(HeldCandidates(), Candidates(usable), gate_d2, too_close_m);
  int added = 0;
  for (std::size_t i = 0; i < usable.size(); ++i) {
    if (match[i] == filters::kTooClose) continue;
    filters::MapLandmark l = usable[i];
    if (match[i] >= 0) {
      l.track_id = held_[match[i]].landmark.track_id;
      held_[match[i]].landmark = l;
    } else {
      l.track_id = next_track_++;
      held_.push_back({l, 0});
      ++added;
    }
  }
  return added;
}

void PeerLandmarks::AppendUnmatched(std::vector<filters::MapLandmark>* map, double gate_d2, double too_close_m) const {
  if (held_.empty()) return;
  const std::vector<int> match = filters::MatchLandmarks(Candidates(*map), HeldCandidates(), gate_d2, too_close_m);
  for (std::size_t i = 0; i < held_.size(); ++i) {
    if (match[i] == -1) map->push_back(held_[i].landmark);
  }
}

Look LookFor(const filters::MapLandmark& landmark, const common::Pose2& pose, const Eigen::Matrix2d& pose_xy,
             double heading_var, const std::vector<common::LandmarkDetection>& readings,
             const common::LidarOptions& lidar, double gate_d2) {
  const Eigen::Vector2d l = landmark.mean.head<2>();
  const common::RangeBearing h = common::MeasureRangeBearing(pose, l);
  if (!WellInView(h, lidar)) return Look::kOutOfView;
  const double bearing_var = lidar.bearing_noise_sd_rad * lidar.bearing_noise_sd_rad + heading_var;
  const double s2 = lidar.range_noise_sd_m * lidar.range_noise_sd_m + h.range_m * h.range_m * bearing_var;
  const Eigen::Matrix2d info =
      (landmark.covariance.topLeftCorner<2, 2>() + pose_xy + s2 * Eigen::Matrix2d::Identity()).inverse();
  const bool explained = std::any_of(readings.begin(), readings.end(), [&](const common::LandmarkDetection& z) {
    const Eigen::Vector2d d = common::PointFromRangeBearing(pose, {z.range_m, z.bearing_rad}) - l;
    return d.dot(info * d) <= gate_d2;
  });
  return explained ? Look::kExplained : Look::kMissed;
}

void PeerLandmarks::CountMisses(const common::Pose2& pose, const Eigen::Matrix2d& pose_xy, double heading_var,
                                const std::vector<common::LandmarkDetection>& readings,
                                const common::LidarOptions& lidar, double gate_d2) {
  const int drop_after = MissesToDrop(lidar.detection_probability);
  for (Held& held : held_) {
    const Look look = LookFor(held.landmark, pose, pose_xy, heading_var, readings, lidar, gate_d2);
    if (look != Look::kOutOfView) held.misses = look == Look::kExplained ? 0 : held.misses + 1;
  }
  held_.erase(std::remove_if(held_.begin(), held_.end(), [&](const Held& h) { return h.misses >= drop_after; }),
              held_.end());
}

std::vector<filters::MatchCandidate> PeerLandmarks::HeldCandidates() const {
  std::vector<filters::MatchCandidate> out;
  out.reserve(held_.size());
  for (const Held& h : held_) out.push_back(filters::CandidateOf(h.landmark));
  return out;
}

int PeerLandmarks::MissesToDrop(double detection_probability) {
  const double miss = 1.0 - detection_probability;
  if (!(miss > 0.0)) return 2;
  if (miss >= 1.0) return std::numeric_limits<int>::max();  // it never sees anything
  return std::max(2, static_cast<int>(std::ceil(std::log(1e-3) / std::log(miss))));
}

}  // namespace mrslam::robot_agent::smoother
