#pragma once

#include <cstdint>
#include <string>

#include "common/config/scenario_options.h"

namespace mrslam::batch {

// mrslam_batch --slip-recovery: whether each robot's own filter recovers from the scenario's
// slips (robots[].slips). Every seed runs twice in-process, with the slips and without them (the
// same seed), each robot scored in its own frame. For a robot's first slip at step s, let t be
// the first step after s whose scan holds a landmark reading; the robot has recovered when, at
// step t + 30 (or the run's last step), its position error is below twice the error of the run
// without the slip and its heading error is within 5 degrees. Prints per slipping robot in how
// many seeds it recovered and the median errors at that step; the JSON holds every seed's.
int PrintSlipRecovery(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                      const std::string& json_path);

}  // namespace mrslam::batch
