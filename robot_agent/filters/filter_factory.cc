#include "robot_agent/filters/filter_factory.h"

#include "robot_agent/filters/ekf_slam.h"
#include "robot_agent/filters/fastslam.h"

namespace mrslam::robot_agent::filters {

std::unique_ptr<SlamFilter> CreateFilter(const common::ScenarioOptions& options, const std::string& robot_id,
                                         std::uint64_t seed) {
  if (options.filter.type == "fastslam") return CreateFastSlam(options, robot_id, seed);
  if (options.filter.type == "ekf") return CreateEkfSlam(options, robot_id, /*ela=*/false);
  if (options.filter.type == "ekf_ela") return CreateEkfSlam(options, robot_id, /*ela=*/true);
  return nullptr;
}

}  // namespace mrslam::robot_agent::filters
