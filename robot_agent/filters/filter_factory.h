#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent::filters {

// Creates the filter the options ask for (options.filter.type), with a random stream derived
// from (seed, options.robot_id). Returns nullptr for an unknown type.
std::unique_ptr<SlamFilter> CreateFilter(const AgentOptions& options, std::uint64_t seed);

}  // namespace mrslam::robot_agent::filters
