// world_sim: steps a scenario's world and publishes every robot's sensors and the ground truth
// over DDS (see docs/dds.md: topics and lockstep).
#include <sstream>

#include <spdlog/spdlog.h>

#include "common/app.h"
#include "common/config/scenario_flags.h"
#include "common/dds/participant.h"
#include "common/logging.h"
#include "world_sim/node/sim_node.h"

int main(int argc, char** argv) {
  using namespace mrslam;
  CLI::App app{"mrslam world simulator: publishes each robot's lidar, IMU and odometry, and the truth"};
  common::CommonFlags flags;
  common::AddCommonFlags(app, &flags);
  int steps = -1;
  std::string agents = "all";
  int truth_readers = 0;
  app.add_option("--steps", steps, "Number of steps (overrides run.steps)");
  app.add_option("--wait-readers", truth_readers,
                 "Before step 1, wait until this many readers (the evaluator) match the truth topic");
  app.add_option("--agents", agents, "Comma-separated agents in the lockstep barrier: 'all' (default) or 'none'");
  return common::RunMain("world_sim", app, argc, argv, [&] {
    common::SetupLogging("world_sim", flags.log_level);
    if (steps >= 0) flags.overrides.push_back("run.steps=" + std::to_string(steps));
    const auto scenario = common::LoadScenarioFromFlags(flags);
    world_sim::SimNodeOptions options;
    options.domain = mrslam::dds::ResolveDomain(scenario.run.domain, flags.domain);
    options.shared_memory = flags.shared_memory;
    options.truth_readers = truth_readers;
    if (agents == "all") {
      for (const auto& r : scenario.robots) options.agents.push_back(r.id);
    } else if (agents != "none") {
      std::stringstream ss(agents);
      for (std::string id; std::getline(ss, id, ',');) {
        if (scenario.RobotIndex(id) < 0) throw std::runtime_error("--agents: unknown robot id '" + id + "'");
        options.agents.push_back(id);
      }
    }
    const auto& stop = common::InstallStopHandler();
    world_sim::SimNode node(scenario, options);
    if (!node.Run(stop)) {
      spdlog::warn("stopped before the end of the run");
      return 130;
    }
    return 0;
  });
}
