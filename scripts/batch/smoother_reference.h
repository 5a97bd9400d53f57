#pragma once

#include <cstdint>
#include <string>

#include "common/config/scenario_options.h"

namespace mrslam::batch {

// mrslam_batch --smoother: each robot's error under the MAP smoother of the whole run (its
// definition beside RunSmootherSeed in smoother_reference.cc), jointly and alone, and the online
// yardstick of each robot alone (each pose from the data up to it), with the configured odometry
// calibration and with it estimated: median and 90th percentile over the
// seeds per robot; the JSON also gets, per seed, every robot's frame as the joint estimate (as
// configured) places it in the first robot's frame.
int PrintSmoother(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                  const std::string& json_path);

}  // namespace mrslam::batch
