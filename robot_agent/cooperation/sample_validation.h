#pragma once

#include <string>

#include "common/sensor_types.h"

namespace mrslam::robot_agent::cooperation {

// Removes the malformed parts of a robot's samples before the filter sees them: detections with
// a non-finite or negative range or a non-finite bearing, robot detections without a seen id,
// odometry segments with non-finite values or a non-positive dt, IMU readings with non-finite
// values. Returns how many items were removed (each is a rejected sample).
int SanitizeLidar(common::LidarScan* scan);
int SanitizeOdometry(common::Odometry* odometry);
int SanitizeImu(common::ImuSamples* imu);

// Why a whole message is rejected before buffering: it names another robot, or a step that was
// already processed. Empty when the stamp is acceptable.
std::string StampProblem(const common::Stamp& stamp, const std::string& own_robot_id, std::uint32_t next_step);

}  // namespace mrslam::robot_agent::cooperation
