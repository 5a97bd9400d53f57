#include "robot_agent/filters/slam_filter.h"

#include <cmath>
#include <cstddef>
#include <limits>

namespace mrslam::robot_agent::filters {

void Io(common::Archive& ar, MapLandmark& l) {
  ar(l.track_id, l.landmark_id, l.mean, l.covariance, l.v_mps, l.w_radps, l.motion, l.moving, l.tentative,
     l.last_seen_step, l.first_seen_step, l.origin_robot, l.origin_track);
}

void Io(common::Archive& ar, MovedLandmark& m) { ar(m.step, m.track_id, m.landmark_id, m.position); }

void Io(common::Archive& ar, FilterEstimate& e) {
  ar(e.step, e.time_s, e.pose, e.covariance, e.effective_sample_size, e.particles, e.landmarks, e.labels_detections,
     e.detection_tracks);
}

std::size_t EstimateBytes(const FilterEstimate& e) {
  return ElementBytes(e.landmarks) + ElementBytes(e.detection_tracks);
}

int NearestKnownKinematics(const std::vector<KnownKinematics>& candidates, double v_mps, double w_radps) {
  int nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const double d = std::abs(candidates[c].v_mps - v_mps) + std::abs(candidates[c].w_radps - w_radps);
    if (d < best) {
      best = d;
      nearest = static_cast<int>(c);
    }
  }
  return nearest;
}

}  // namespace mrslam::robot_agent::filters
