#pragma once

#include <string>

#include "common/sensor_types.h"

namespace mrslam::robot_agent::cooperation {

// Removes the malformed parts of a robot's step before the filter sees them: detections with a
// non-finite or negative range or a non-finite bearing or time, robot detections without a seen
// id, odometry segments with non-finite values or a non-positive dt, IMU readings with non-finite
// values. Returns how many items were removed (each is a rejected sample).
int SanitizeSensorStep(common::SensorStep* step);

// Why a whole sample is malformed: it names another robot, or its time is not finite. Empty when
// the stamp is acceptable (whether its step is wanted is StepSlots' to say).
std::string StampProblem(const common::Stamp& stamp, const std::string& own_robot_id);

}  // namespace mrslam::robot_agent::cooperation
