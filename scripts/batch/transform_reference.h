#pragma once

#include <cstdint>
#include <string>

#include "common/config/scenario_options.h"

namespace mrslam::batch {

// mrslam_batch --transform-reference: per ordered pair of robots, the error of the transform
// T(G_i <- G_j) at the end of their first encounter (docs/cooperation.md) as the joint MAP
// reference of both robots holds it: the best that "everything both robots know" allows (with a
// landmark_field, from its static landmarks: the movers' readings are left out). Prints the
// median and 90th percentile over the seeds where the pair met; the JSON also holds each met
// pair's transform per seed.
int PrintTransformReference(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds,
                            int threads, const std::string& json_path);

}  // namespace mrslam::batch
