#pragma once

#include <string>

#include "mrslam.h"
#include "robot_agent/core/slam_filter.h"

// Conversions between a filter's estimate and the Estimate message (free functions at the edge).
namespace mrslam::robot_agent {

msg::Estimate ToMsg(const FilterEstimate& estimate, const std::string& robot_id, const std::string& filter);
FilterEstimate FromMsg(const msg::Estimate& estimate);

}  // namespace mrslam::robot_agent
