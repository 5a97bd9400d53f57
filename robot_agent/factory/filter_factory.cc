#include "robot_agent/factory/filter_factory.h"

#include "robot_agent/filters/ekf_slam.h"
#include "robot_agent/filters/fastslam.h"
#include "robot_agent/smoother/online_smoother.h"

namespace mrslam::robot_agent::factory {

std::unique_ptr<filters::SlamFilter> CreateFilter(const AgentOptions& options, std::uint64_t seed) {
  if (options.filter.type == "fastslam") return filters::CreateFastSlam(options, seed);
  if (options.filter.type == "ekf") return filters::CreateEkfSlam(options, /*ela=*/false);
  if (options.filter.type == "ekf_ela") return filters::CreateEkfSlam(options, /*ela=*/true);
  if (options.filter.type == "smoother") return std::make_unique<smoother::OnlineSmoother>(options, seed);
  return nullptr;
}

}  // namespace mrslam::robot_agent::factory
