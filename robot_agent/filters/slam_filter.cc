#include "robot_agent/filters/slam_filter.h"

#include <cmath>
#include <cstddef>
#include <limits>

namespace mrslam::robot_agent::filters {

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
