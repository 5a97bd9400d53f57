#pragma once

#include <string>

#include "mrslam.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/filters/slam_filter.h"

// Conversions between a filter's estimate and the Estimate message (free functions at the edge).
namespace mrslam::robot_agent {

msg::Estimate ToMsg(const filters::FilterEstimate& estimate, const std::string& robot_id, const std::string& filter);
filters::FilterEstimate FromMsg(const msg::Estimate& estimate);

msg::LandmarkEstimate ToMsg(const filters::MapLandmark& landmark);
filters::MapLandmark FromMsg(const msg::LandmarkEstimate& landmark);
msg::RendezvousEvent ToMsg(const cooperation::RendezvousEvent& event);
cooperation::RendezvousEvent FromMsg(const msg::RendezvousEvent& event);
msg::RendezvousEvent ToMsg(const cooperation::FrameTransform& transform);
cooperation::FrameTransform TransformFromMsg(const msg::RendezvousEvent& event);

msg::RelativeMeasurement ToMsg(const cooperation::RelativeMeasurement& m);
cooperation::RelativeMeasurement FromMsg(const msg::RelativeMeasurement& m);
msg::MapSnapshot ToMsg(const cooperation::MapSnapshot& m);
cooperation::MapSnapshot FromMsg(const msg::MapSnapshot& m);
msg::LandmarkMovedNotice ToMsg(const cooperation::LandmarkMovedNotice& m);
cooperation::LandmarkMovedNotice FromMsg(const msg::LandmarkMovedNotice& m);

}  // namespace mrslam::robot_agent
