#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "common/config/scenario_options.h"
#include "robot_agent/filters/slam_filter.h"

namespace mrslam::robot_agent::filters {

// Creates the filter the scenario asks for (options.filter.type), for robot robot_id, with a
// random stream derived from (seed, robot_id). Returns nullptr for an unknown type.
std::unique_ptr<SlamFilter> CreateFilter(const common::ScenarioOptions& options, const std::string& robot_id,
                                         std::uint64_t seed);

}  // namespace mrslam::robot_agent::filters
