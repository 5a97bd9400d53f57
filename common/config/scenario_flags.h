#pragma once

#include "common/app.h"
#include "common/config/scenario_options.h"

namespace mrslam::common {

// Loads the scenario of --scenario with the --set overrides, then applies --seed.
ScenarioOptions LoadScenarioFromFlags(const CommonFlags& flags);

}  // namespace mrslam::common
