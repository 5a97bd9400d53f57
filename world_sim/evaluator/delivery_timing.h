#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

// How fast a run's estimates reached the evaluator, from DDS's timestamps (no DDS types here).
namespace mrslam::evaluator {

// How many late estimates' steps a robot's summary names (where they fall: the start, a meeting,
// the map's growth).
constexpr std::size_t kMaxLateSteps = 20;

// One robot's delivery figures (docs/metrics.md).
struct DeliverySummary {
  double latency_us_median = 0.0;
  double latency_us_p99 = 0.0;
  double estimate_hop_us_median = 0.0;    // received(estimate) - written(estimate)
  double data_hop_us_median = 0.0;        // received(sensor step, by the agent) - written(sensor step)
  double agent_overhead_us_median = 0.0;  // latency - data hop - estimate hop, per step
  int late_estimates = 0;
  std::vector<std::uint32_t> late_steps;  // the steps of the first kMaxLateSteps late estimates
  std::size_t timed_steps = 0;            // the steps whose latency is known
};

// Takes when world_sim wrote each step and each robot's sensor data, and when each estimate was
// written by its agent and received here; reports per robot:
// - latency: received(estimate of step k) - written(step k) - the agent's processing time of the
//   step, where written(step k) is the later of world_sim's write of the step's truth, which it
//   writes immediately before the step's clock, and of the robot's sensor step (the first errs
//   high by the gap to the clock, microseconds);
// - late estimates: estimates of step k written after world_sim wrote the robot's sensor step
//   k + 1, i.e. after the next step's data started to flow;
// - the estimate's hop: received(estimate) - written(estimate), the DDS hop from the agent's write
//   to this process (a part of the latency, and its yardstick);
// - the data's hop, as the agent reports it: its reception of the sensor step less world_sim's
//   write of it, the other DDS hop of the latency;
// - the agent's overhead: per step, the latency less both hops: what the agent adds beyond its
//   processing (taking the data from DDS's thread, waiting for what the step needs, converting
//   and writing the estimate).
// Times are nanoseconds since the Unix epoch from the system clock, comparable on one host; 0
// means unknown and leaves the step out. Each robot's estimates come in step order. A time is
// held only until what it is compared with arrives (or can no longer arrive): per step only each
// robot's latency stays (for the percentiles). Pure.
// One estimate's times, as delivered (0: unknown).
struct EstimateTiming {
  std::int64_t written_ns = 0;   // the agent's write (DDS's source timestamp)
  std::int64_t received_ns = 0;  // this process's reception
  double processing_ms = 0.0;    // the agent's CPU time of the step
  double data_hop_us = 0.0;      // the step's sensor step: the agent's reception less its write
};

class DeliveryTiming {
 public:
  explicit DeliveryTiming(const std::vector<std::string>& robot_ids);

  void StepWritten(std::uint32_t step, std::int64_t written_ns);
  void SensorWritten(const std::string& robot_id, std::uint32_t step, std::int64_t written_ns);
  void EstimateDelivered(const std::string& robot_id, std::uint32_t step, const EstimateTiming& times);

  DeliverySummary Summary(const std::string& robot_id) const;
  // Times held, waiting for their counterpart.
  std::size_t Held() const;

 private:
  struct Arrival {
    std::int64_t ns = 0;   // received - processing
    double hops_us = 0.0;  // the data's and the estimate's hops (0: either unknown)
  };
  struct RobotTiming {
    std::map<std::uint32_t, std::int64_t> sensor_written;    // awaiting the previous step's estimate
    std::map<std::uint32_t, std::int64_t> estimate_written;  // awaiting the next step's sensor data
    std::map<std::uint32_t, std::int64_t> data_written;      // the step's sensor step, awaiting its estimate
    std::map<std::uint32_t, Arrival> arrival;                // awaiting the step
    bool any_estimate = false;
    std::uint32_t newest_estimate = 0;
    std::vector<double> latency_us;
    std::vector<double> estimate_hop_us;
    std::vector<double> data_hop_us;
    std::vector<double> overhead_us;
    int late = 0;
    std::vector<std::uint32_t> late_steps;  // the first kMaxLateSteps
  };
  // Judges whether the estimate of step k was late, if both times are known; lets them go.
  static void JudgeLate(RobotTiming* robot, std::uint32_t step);
  // Adds the latency of the robot's step k once its estimate, its data and the step are in.
  void TimeStep(RobotTiming* robot, std::uint32_t step);
  // Lets go of the steps' times every robot is past.
  void Prune();

  std::map<std::uint32_t, std::int64_t> steps_;
  std::map<std::string, RobotTiming> robots_;
};

}  // namespace mrslam::evaluator
