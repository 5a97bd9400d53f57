#include "robot_agent/cooperation/sample_validation.h"

#include <algorithm>
#include <cmath>

namespace mrslam::robot_agent::cooperation {

namespace {
template <typename T, typename Bad>
int EraseIf(std::vector<T>* items, Bad bad) {
  const auto before = items->size();
  items->erase(std::remove_if(items->begin(), items->end(), bad), items->end());
  return static_cast<int>(before - items->size());
}
bool Finite(double v) { return std::isfinite(v); }

int SanitizeLidar(common::LidarScan* scan) {
  return EraseIf(&scan->landmarks,
                 [](const common::LandmarkDetection& d) {
                   return !Finite(d.range_m) || d.range_m < 0.0 || !Finite(d.bearing_rad) || !Finite(d.time_s);
                 }) +
         EraseIf(&scan->robots, [](const common::RobotDetection& d) {
           return !Finite(d.range_m) || d.range_m < 0.0 || !Finite(d.bearing_rad) || d.seen_robot_id.empty();
         });
}

int SanitizeOdometry(common::Odometry* odometry) {
  return EraseIf(&odometry->segments, [](const common::OdometrySegment& g) {
    return !Finite(g.v_mps) || !Finite(g.w_radps) || !Finite(g.dt_s) || g.dt_s <= 0.0 || !Finite(g.time_s);
  });
}

int SanitizeImu(common::ImuSamples* imu) {
  return EraseIf(&imu->readings, [](const common::ImuReading& r) {
    return !Finite(r.gyro_z_radps) || !Finite(r.accel_x_mps2) || !Finite(r.accel_y_mps2) || !Finite(r.time_s);
  });
}

}  // namespace

int SanitizeSensorStep(common::SensorStep* step) {
  return SanitizeLidar(&step->lidar) + SanitizeImu(&step->imu) + SanitizeOdometry(&step->odometry);
}

std::string StampProblem(const common::Stamp& stamp, const std::string& own_robot_id) {
  if (stamp.robot_id != own_robot_id)
    return "sample for robot '" + stamp.robot_id + "' on " + own_robot_id + "'s topic";
  if (!std::isfinite(stamp.time_s)) return "sample of step " + std::to_string(stamp.step) + " has a non-finite time";
  return {};
}

}  // namespace mrslam::robot_agent::cooperation
