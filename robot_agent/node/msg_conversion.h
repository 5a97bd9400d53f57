#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "mrslam.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/filters/slam_filter.h"

// Conversions between the agent's estimates and its messages (free functions at the edge).
namespace mrslam::robot_agent {

msg::Estimate ToMsg(const filters::FilterEstimate& estimate, const std::string& robot_id, const std::string& filter);
filters::FilterEstimate FromMsg(const msg::Estimate& estimate);

msg::LandmarkEstimate ToMsg(const filters::MapLandmark& landmark);
filters::MapLandmark FromMsg(const msg::LandmarkEstimate& landmark);
msg::RendezvousEvent ToMsg(const cooperation::RendezvousEvent& event);
// Cooperation::data_held, per robot in id order.
std::vector<msg::DataHeld> DataHeldMsg(const std::map<std::string, std::uint32_t>& held);
cooperation::RendezvousEvent FromMsg(const msg::RendezvousEvent& event);
msg::RendezvousEvent ToMsg(const cooperation::FrameTransform& transform);
cooperation::FrameTransform TransformFromMsg(const msg::RendezvousEvent& event);

msg::RelativeMeasurement ToMsg(const cooperation::RelativeMeasurement& m);
cooperation::RelativeMeasurement FromMsg(const msg::RelativeMeasurement& m);
msg::MapSnapshot ToMsg(const cooperation::MapSnapshot& m);
cooperation::MapSnapshot FromMsg(const msg::MapSnapshot& m);
msg::LandmarkMovedNotice ToMsg(const cooperation::LandmarkMovedNotice& m);
msg::FactorBatch ToMsg(const cooperation::FactorBatch& b);
cooperation::FactorBatch FromMsg(const msg::FactorBatch& m);

// A final trajectory as FinalTrajectory chunks of at most kFinalTrajectoryChunkPoses poses,
// stamped (robot_id, step, time_s); each pose's time from step_times (0 where unknown).
inline constexpr std::size_t kFinalTrajectoryChunkPoses = 1000;
std::vector<msg::FinalTrajectory> FinalTrajectoryChunks(const std::vector<std::pair<int, common::Pose2>>& path,
                                                        const std::map<std::uint32_t, double>& step_times,
                                                        const common::Stamp& stamp);
cooperation::LandmarkMovedNotice FromMsg(const msg::LandmarkMovedNotice& m);

}  // namespace mrslam::robot_agent
