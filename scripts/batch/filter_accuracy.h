#pragma once

#include <cstdint>
#include <string>

#include "common/config/scenario_options.h"

namespace mrslam::batch {

// mrslam_batch's default mode: the accuracy of each robot's own filter over the seeds, in-process
// (the scenario's step source and one filter per robot, no DDS), each robot scored as the
// evaluator scores it (evaluator::RobotScorer). With reference, the approximately ideal filter
// (the oracle BatchSmoother: batch MAP with oracle association and kinematics) replaces each
// robot's own filter on the same data. Prints the median and 90th percentile over the seeds per
// robot and metric; the JSON (json_path, if any) also holds every seed's values.
int PrintFilterAccuracy(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                        const std::string& json_path, bool reference);

}  // namespace mrslam::batch
