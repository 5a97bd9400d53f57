#include "common/config/scenario_flags.h"

#include <cstdint>

namespace mrslam::common {

ScenarioOptions LoadScenarioFromFlags(const CommonFlags& flags) {
  ScenarioOptions options = LoadScenario(flags.scenario, flags.overrides);
  if (flags.seed >= 0) options.seed = static_cast<std::uint64_t>(flags.seed);
  return options;
}

}  // namespace mrslam::common
