#pragma once

#include <deque>
#include <vector>

#include "common/archive.h"
#include "common/sensor_types.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent::filters {

// The motion a step's wheel odometry stands for, after the calibration of the commands
// (filter.odometry_scale, odometry_turn_scale, odometry_lag_s): the robot moves at
// odometry_scale times the commanded forward speed and odometry_turn_scale times the commanded
// turn rate, odometry_lag_s after the command. Segments that are not finite or not of positive
// length are ignored. Keeps the commands not yet played out (a lag's worth). Pure.
class OdometryCalibration {
 public:
  struct Motion {
    double v_mps, w_radps, dt_s;
  };

  explicit OdometryCalibration(const FilterOptions& filter);

  // The motion over the step [time_s - step_dt_s, time_s) that ends with `odometry`'s
  // interval: the calibrated commands of that interval, or with a lag those of [time_s - dt -
  // lag, time_s - lag), zero velocity where none was issued. Never empty.
  std::vector<Motion> Step(const common::Odometry& odometry, double time_s, double step_dt_s);

  void Io(common::Archive& ar) { ar(scale_, turn_scale_, lag_s_, pending_); }

 private:
  double scale_, turn_scale_, lag_s_;
  std::deque<common::OdometrySegment> pending_;  // lag > 0: calibrated commands to play out
};

}  // namespace mrslam::robot_agent::filters
