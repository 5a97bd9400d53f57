#include "robot_agent/filters/odometry_calibration.h"

#include <algorithm>
#include <cmath>

namespace mrslam::robot_agent::filters {

OdometryCalibration::OdometryCalibration(const FilterOptions& filter)
    : scale_(filter.odometry_scale), turn_scale_(filter.odometry_turn_scale), lag_s_(filter.odometry_lag_s) {}

std::vector<OdometryCalibration::Motion> OdometryCalibration::Step(const common::Odometry& odometry, double time_s,
                                                                   double step_dt_s) {
  std::vector<Motion> out;
  for (const auto& s : odometry.segments) {
    if (std::isfinite(s.v_mps) && std::isfinite(s.w_radps) && std::isfinite(s.time_s) && s.dt_s > 0.0) {
      if (lag_s_ > 0.0) {
        pending_.push_back({s.time_s, s.dt_s, scale_ * s.v_mps, turn_scale_ * s.w_radps});
      } else {
        out.push_back({scale_ * s.v_mps, turn_scale_ * s.w_radps, s.dt_s});
      }
    }
  }
  if (lag_s_ > 0.0) {
    const double to = time_s - lag_s_;
    const double from = to - step_dt_s;
    double cursor = from;
    for (const auto& h : pending_) {
      const double start = std::max(h.time_s, cursor);
      const double end = std::min(h.time_s + h.dt_s, to);
      if (end <= start) continue;
      if (start > cursor) out.push_back({0.0, 0.0, start - cursor});
      out.push_back({h.v_mps, h.w_radps, end - start});
      cursor = end;
    }
    if (to > cursor) out.push_back({0.0, 0.0, to - cursor});
    while (!pending_.empty() && pending_.front().time_s + pending_.front().dt_s <= to) pending_.pop_front();
  }
  if (out.empty()) out.push_back({0.0, 0.0, step_dt_s});
  return out;
}

}  // namespace mrslam::robot_agent::filters
