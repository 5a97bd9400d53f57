#include "world_sim/evaluator/delivery_timing.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "world_sim/evaluator/metrics.h"

namespace mrslam::evaluator {

namespace {
// Erases the times of steps before `step` that have no counterpart in `partner`.
template <typename Times, typename Partner>
void EraseUnpaired(Times* times, const Partner& partner, std::uint32_t step) {
  for (auto it = times->begin(); it != times->end() && it->first < step;) {
    it = partner.count(it->first) > 0 ? std::next(it) : times->erase(it);
  }
}
}  // namespace

DeliveryTiming::DeliveryTiming(const std::vector<std::string>& robot_ids) {
  for (const auto& id : robot_ids) robots_[id];
}

void DeliveryTiming::StepWritten(std::uint32_t step, std::int64_t written_ns) {
  if (written_ns <= 0) return;
  steps_[step] = written_ns;
  for (auto& [id, robot] : robots_) TimeStep(&robot, step);
  Prune();
}

void DeliveryTiming::SensorWritten(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns) {
  RobotTiming& robot = robots_.at(robot_id);
  if (written_ns <= 0) return;
  // Step k's data judges the estimate of step k - 1, which may have come, be on its way or be
  // lost (estimates come in step order: lost once a later one came). It may be taken after
  // the estimate of its own step (taken in a batch).
  robot.sensor_written[step] = written_ns;
  if (step > 0) JudgeLate(&robot, step - 1);
  if (robot.any_estimate && step <= robot.newest_estimate + 1) robot.sensor_written.erase(step);
  // The robot's data come in step order: an estimate still waiting for an earlier step's lost them.
  EraseUnpaired(&robot.arrival, robot.data_written, step);
  if (!robot.any_estimate || step > robot.newest_estimate || robot.arrival.count(step) > 0) {
    robot.data_written[step] = written_ns;
    TimeStep(&robot, step);
  }
  Prune();
}

void DeliveryTiming::EstimateDelivered(const std::string& robot_id, std::uint32_t step, const EstimateTiming& times) {
  RobotTiming& robot = robots_.at(robot_id);
  // Nanoseconds since the epoch exceed a double's exact integers: differences first.
  double hops_us = 0.0;
  const bool data_hop = std::isfinite(times.data_hop_us) && times.data_hop_us > 0.0;
  if (data_hop) robot.data_hop_us.push_back(times.data_hop_us);
  if (times.received_ns > 0 && times.written_ns > 0) {
    const double hop_us = static_cast<double>(times.received_ns - times.written_ns) * 1e-3;
    robot.estimate_hop_us.push_back(hop_us);
    if (data_hop) hops_us = hop_us + times.data_hop_us;
  }
  if (times.received_ns > 0 && std::isfinite(times.processing_ms)) {
    robot.arrival[step] = {times.received_ns - std::llround(times.processing_ms * 1e6), hops_us};
    TimeStep(&robot, step);
  }
  if (times.written_ns > 0) {
    robot.estimate_written[step] = times.written_ns;
    JudgeLate(&robot, step);
  }
  robot.any_estimate = true;
  robot.newest_estimate = std::max(robot.newest_estimate, step);
  // Sensor data of steps up to this one can no longer meet an earlier estimate, nor the data of
  // earlier steps their own estimate (in or lost).
  robot.sensor_written.erase(robot.sensor_written.begin(), robot.sensor_written.upper_bound(step));
  EraseUnpaired(&robot.data_written, robot.arrival, step);
  Prune();
}

void DeliveryTiming::TimeStep(RobotTiming* robot, std::uint32_t step) {
  const auto arrival = robot->arrival.find(step);
  const auto data = robot->data_written.find(step);
  const auto written = steps_.find(step);
  if (arrival == robot->arrival.end() || data == robot->data_written.end() || written == steps_.end()) return;
  const std::int64_t from = std::max(written->second, data->second);
  const double latency_us = static_cast<double>(arrival->second.ns - from) * 1e-3;
  robot->latency_us.push_back(latency_us);
  if (arrival->second.hops_us > 0.0) robot->overhead_us.push_back(latency_us - arrival->second.hops_us);
  robot->arrival.erase(arrival);
  robot->data_written.erase(data);
}

void DeliveryTiming::JudgeLate(RobotTiming* robot, std::uint32_t step) {
  const auto estimate = robot->estimate_written.find(step);
  const auto next = robot->sensor_written.find(step + 1);
  if (estimate == robot->estimate_written.end() || next == robot->sensor_written.end()) return;
  if (estimate->second > next->second) {
    ++robot->late;
    if (robot->late_steps.size() < kMaxLateSteps) robot->late_steps.push_back(step);
  }
  robot->estimate_written.erase(estimate);
  robot->sensor_written.erase(next);
}

void DeliveryTiming::Prune() {
  // Every robot's estimates of steps before all_past are in or lost, and timed or lost.
  std::uint32_t all_past = 0;
  bool first = true;
  for (const auto& [id, robot] : robots_) {
    std::uint32_t past = robot.any_estimate ? robot.newest_estimate + 1 : 0;
    if (!robot.arrival.empty()) past = std::min(past, robot.arrival.begin()->first);
    all_past = first ? past : std::min(all_past, past);
    first = false;
  }
  steps_.erase(steps_.begin(), steps_.lower_bound(all_past));
}

DeliverySummary DeliveryTiming::Summary(const std::string& robot_id) const {
  DeliverySummary out;
  const auto robot = robots_.find(robot_id);
  if (robot == robots_.end()) return out;
  out.late_estimates = robot->second.late;
  out.late_steps = robot->second.late_steps;
  out.timed_steps = robot->second.latency_us.size();
  if (!robot->second.latency_us.empty()) {
    out.latency_us_median = Median(robot->second.latency_us);
    out.latency_us_p99 = Percentile(robot->second.latency_us, 99.0);
  }
  if (!robot->second.estimate_hop_us.empty()) out.estimate_hop_us_median = Median(robot->second.estimate_hop_us);
  if (!robot->second.data_hop_us.empty()) out.data_hop_us_median = Median(robot->second.data_hop_us);
  if (!robot->second.overhead_us.empty()) out.agent_overhead_us_median = Median(robot->second.overhead_us);
  return out;
}

std::size_t DeliveryTiming::Held() const {
  std::size_t n = steps_.size();
  for (const auto& [id, robot] : robots_) {
    n += robot.sensor_written.size() + robot.estimate_written.size() + robot.arrival.size() + robot.data_written.size();
  }
  return n;
}

}  // namespace mrslam::evaluator
