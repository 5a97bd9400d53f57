#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

// How fast a run's estimates reached the evaluator, from DDS's timestamps (no DDS types here).
namespace mrslam::evaluator {

// One robot's delivery figures (docs/metrics.md).
struct DeliverySummary {
  double latency_us_median = 0.0;
  double latency_us_p99 = 0.0;
  int late_estimates = 0;
  std::size_t timed_steps = 0;  // the steps whose latency is known
};

// Collects when world_sim wrote each step and each robot's sensor data, and when each estimate
// was written by its agent and received here; reports per robot:
// - latency: received(estimate of step k) - written(step k) - the agent's processing time of the
//   step, where written(step k) is world_sim's write of the step's truth, which it writes
//   immediately before the step's clock (so the figure errs high by that gap, microseconds);
// - late estimates: estimates of step k written after world_sim wrote step k + 1's first sensor
//   message for that robot (its odometry), i.e. after the next step's data started to flow.
// Times are nanoseconds since the Unix epoch from the system clock, comparable on one host; 0
// means unknown and leaves the step out. Pure.
class DeliveryTiming {
 public:
  void StepWritten(std::uint32_t step, std::int64_t written_ns);
  void SensorWritten(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns);
  void EstimateDelivered(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns,
                         std::int64_t received_ns, double processing_ms);

  DeliverySummary Summary(const std::string& robot_id) const;

 private:
  struct Delivery {
    std::int64_t written_ns = 0;
    std::int64_t received_ns = 0;
    double processing_ms = 0.0;
  };
  std::map<std::uint32_t, std::int64_t> steps_;
  std::map<std::string, std::map<std::uint32_t, std::int64_t>> sensors_;
  std::map<std::string, std::map<std::uint32_t, Delivery>> estimates_;
};

}  // namespace mrslam::evaluator
