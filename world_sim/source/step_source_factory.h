#pragma once

#include <memory>

#include "common/config/scenario_options.h"
#include "world_sim/core/step_source.h"

namespace mrslam::world_sim {

// The scenario's source: the simulated world, or the recorded data set when replay.dir is set
// (throws MrclamError when one of its files is missing).
std::unique_ptr<StepSource> MakeStepSource(const common::ScenarioOptions& options);

}  // namespace mrslam::world_sim
