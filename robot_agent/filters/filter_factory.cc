#include "robot_agent/filters/filter_factory.h"

#include "robot_agent/filters/ekf_slam.h"
#include "robot_agent/filters/fastslam.h"

namespace mrslam::robot_agent::filters {

std::unique_ptr<SlamFilter> CreateFilter(const AgentOptions& options, std::uint64_t seed) {
  if (options.filter.type == "fastslam") return CreateFastSlam(options, seed);
  if (options.filter.type == "ekf") return CreateEkfSlam(options, /*ela=*/false);
  if (options.filter.type == "ekf_ela") return CreateEkfSlam(options, /*ela=*/true);
  return nullptr;
}

}  // namespace mrslam::robot_agent::filters
