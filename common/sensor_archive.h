#pragma once

#include "common/archive.h"
#include "common/sensor_types.h"

// The sensor structs in an Archive (archive.h), member by member.
namespace mrslam::common {

inline void Io(Archive& ar, Stamp& s) { ar(s.robot_id, s.step, s.time_s); }
inline void Io(Archive& ar, RobotDetection& d) { ar(d.time_s, d.range_m, d.bearing_rad, d.seen_robot_id); }
inline void Io(Archive& ar, LidarScan& s) { ar(s.stamp, s.landmarks, s.robots); }
inline void Io(Archive& ar, ImuSamples& s) { ar(s.stamp, s.readings); }
inline void Io(Archive& ar, Odometry& o) { ar(o.stamp, o.segments); }
inline void Io(Archive& ar, SensorStep& s) { ar(s.lidar, s.imu, s.odometry); }

}  // namespace mrslam::common
