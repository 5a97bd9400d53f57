#include "world_sim/source/step_source_factory.h"

#include "world_sim/core/world.h"
#include "world_sim/replay/mrclam_replay.h"

namespace mrslam::world_sim {

std::unique_ptr<StepSource> MakeStepSource(const common::ScenarioOptions& options) {
  if (options.replay.enabled) return std::make_unique<MrclamReplay>(options);
  return std::make_unique<World>(options);
}

}  // namespace mrslam::world_sim
