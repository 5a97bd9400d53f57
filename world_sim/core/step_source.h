#pragma once

#include <cstdint>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/sensor_types.h"

namespace mrslam::world_sim {

// What the simulator's DDS node publishes from: a source of per-step sensor samples and of the
// ground truth. The simulated World and the MRCLAM replay implement it. Pure: no DDS.
class StepSource {
 public:
  virtual ~StepSource() = default;

  // Advances one step and returns each robot's samples, in scenario order.
  virtual std::vector<common::SensorStep> Step() = 0;
  // The truth now (world frame), with every robot's frame.
  virtual common::GroundTruth Truth() const = 0;
  // Steps taken so far, and the time of the last one.
  virtual std::uint32_t step() const = 0;
  virtual double time_s() const = 0;
};

}  // namespace mrslam::world_sim
