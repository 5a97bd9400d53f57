#pragma once

#include <string>

#include "mrslam.h"
#include "robot_agent/core/peer_messages.h"
#include "robot_agent/core/slam_filter.h"

// Conversions between a filter's estimate and the Estimate message (free functions at the edge).
namespace mrslam::robot_agent {

msg::Estimate ToMsg(const FilterEstimate& estimate, const std::string& robot_id, const std::string& filter);
FilterEstimate FromMsg(const msg::Estimate& estimate);

msg::LandmarkEstimate ToMsg(const MapLandmark& landmark);
MapLandmark FromMsg(const msg::LandmarkEstimate& landmark);
msg::RendezvousEvent ToMsg(const RendezvousEvent& event);
RendezvousEvent FromMsg(const msg::RendezvousEvent& event);
msg::RendezvousEvent ToMsg(const FrameTransform& transform);
FrameTransform TransformFromMsg(const msg::RendezvousEvent& event);

msg::RelativeMeasurement ToMsg(const RelativeMeasurement& m);
RelativeMeasurement FromMsg(const msg::RelativeMeasurement& m);
msg::MapSnapshot ToMsg(const MapSnapshot& m);
MapSnapshot FromMsg(const msg::MapSnapshot& m);
msg::LandmarkMovedNotice ToMsg(const LandmarkMovedNotice& m);
LandmarkMovedNotice FromMsg(const msg::LandmarkMovedNotice& m);

}  // namespace mrslam::robot_agent
