#include "world_sim/evaluator/delivery_timing.h"

#include <vector>

#include "world_sim/evaluator/metrics.h"

namespace mrslam::evaluator {

void DeliveryTiming::StepWritten(std::uint32_t step, std::int64_t written_ns) {
  if (written_ns > 0) steps_[step] = written_ns;
}

void DeliveryTiming::SensorWritten(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns) {
  if (written_ns > 0) sensors_[robot_id][step] = written_ns;
}

void DeliveryTiming::EstimateDelivered(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns,
                                       std::int64_t received_ns, double processing_ms) {
  estimates_[robot_id][step] = {written_ns, received_ns, processing_ms};
}

DeliverySummary DeliveryTiming::Summary(const std::string& robot_id) const {
  DeliverySummary out;
  const auto estimates = estimates_.find(robot_id);
  if (estimates == estimates_.end()) return out;
  const auto sensors = sensors_.find(robot_id);
  std::vector<double> latency_us;
  for (const auto& [step, d] : estimates->second) {
    const auto written = steps_.find(step);
    if (written != steps_.end() && d.received_ns > 0) {
      latency_us.push_back(static_cast<double>(d.received_ns - written->second) * 1e-3 - d.processing_ms * 1e3);
    }
    if (sensors == sensors_.end() || d.written_ns <= 0) continue;
    const auto next = sensors->second.find(step + 1);
    if (next != sensors->second.end() && d.written_ns > next->second) ++out.late_estimates;
  }
  out.timed_steps = latency_us.size();
  if (!latency_us.empty()) {
    out.latency_us_median = Median(latency_us);
    out.latency_us_p99 = Percentile(latency_us, 99.0);
  }
  return out;
}

}  // namespace mrslam::evaluator
