#pragma once

#include <array>

#include <Eigen/Core>

#include "common/sensor_types.h"
#include "mrslam.h"

// Conversions between the DDS messages and the plain structs of the pure cores (free
// functions at the edge, with round-trip tests).
namespace mrslam::dds {

msg::Stamp ToMsg(const common::Stamp& s);
common::Stamp FromMsg(const msg::Stamp& s);
msg::Pose2D ToMsg(const common::Pose2& p);
common::Pose2 FromMsg(const msg::Pose2D& p);
// 3x3 covariances travel row-major as double[9].
std::array<double, 9> CovarianceToMsg(const Eigen::Matrix3d& m);
Eigen::Matrix3d CovarianceFromMsg(const std::array<double, 9>& a);

msg::LidarScan ToMsg(const common::LidarScan& scan);
common::LidarScan FromMsg(const msg::LidarScan& scan);
msg::Odometry ToMsg(const common::Odometry& odom);
common::Odometry FromMsg(const msg::Odometry& odom);
// One message per robot and step, stamped with the odometry's stamp (the simulator stamps the
// three parts alike); each part read back carries the message's stamp.
msg::SensorStep ToMsg(const common::SensorStep& step);
common::SensorStep FromMsg(const msg::SensorStep& step);
msg::GroundTruth ToMsg(const common::GroundTruth& truth);
common::GroundTruth FromMsg(const msg::GroundTruth& truth);

}  // namespace mrslam::dds
