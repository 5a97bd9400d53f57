#include "world_sim/evaluator/delivery_timing.h"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "world_sim/evaluator/metrics.h"

namespace mrslam::evaluator {

namespace {
// Erases the times of steps before `step` that have no counterpart in `partner`.
void EraseUnpaired(std::map<std::uint32_t, std::int64_t>* times, const std::map<std::uint32_t, std::int64_t>& partner,
                   std::uint32_t step) {
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
  EraseUnpaired(&robot.arrival_ns, robot.data_written, step);
  if (!robot.any_estimate || step > robot.newest_estimate || robot.arrival_ns.count(step) > 0) {
    robot.data_written[step] = written_ns;
    TimeStep(&robot, step);
  }
  Prune();
}

void DeliveryTiming::EstimateDelivered(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns,
                                       std::int64_t received_ns, double processing_ms) {
  RobotTiming& robot = robots_.at(robot_id);
  if (received_ns > 0 && written_ns > 0)
    robot.estimate_hop_us.push_back(static_cast<double>(received_ns - written_ns) * 1e-3);
  if (received_ns > 0) {
    // Nanoseconds since the epoch exceed a double's exact integers: differences first.
    robot.arrival_ns[step] = received_ns - std::llround(processing_ms * 1e6);
    TimeStep(&robot, step);
  }
  if (written_ns > 0) {
    robot.estimate_written[step] = written_ns;
    JudgeLate(&robot, step);
  }
  robot.any_estimate = true;
  robot.newest_estimate = std::max(robot.newest_estimate, step);
  // Sensor data of steps up to this one can no longer meet an earlier estimate, nor the data of
  // earlier steps their own estimate (in or lost).
  robot.sensor_written.erase(robot.sensor_written.begin(), robot.sensor_written.upper_bound(step));
  EraseUnpaired(&robot.data_written, robot.arrival_ns, step);
  Prune();
}

void DeliveryTiming::TimeStep(RobotTiming* robot, std::uint32_t step) {
  const auto arrival = robot->arrival_ns.find(step);
  const auto data = robot->data_written.find(step);
  const auto written = steps_.find(step);
  if (arrival == robot->arrival_ns.end() || data == robot->data_written.end() || written == steps_.end()) return;
  const std::int64_t from = std::max(written->second, data->second);
  robot->latency_us.push_back(static_cast<double>(arrival->second - from) * 1e-3);
  robot->arrival_ns.erase(arrival);
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
    if (!robot.arrival_ns.empty()) past = std::min(past, robot.arrival_ns.begin()->first);
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
  return out;
}

std::size_t DeliveryTiming::Held() const {
  std::size_t n = steps_.size();
  for (const auto& [id, robot] : robots_) {
    n += robot.sensor_written.size() + robot.estimate_written.size() + robot.arrival_ns.size() +
         robot.data_written.size();
  }
  return n;
}

}  // namespace mrslam::evaluator
