#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent::factory {

// Creates the estimator the options ask for (options.filter.type: fastslam, ekf, ekf_ela or
// smoother), with a random stream derived from (seed, options.robot_id). Returns nullptr for an
// unknown type.
std::unique_ptr<filters::SlamFilter> CreateFilter(const AgentOptions& options, std::uint64_t seed);

}  // namespace mrslam::robot_agent::factory
