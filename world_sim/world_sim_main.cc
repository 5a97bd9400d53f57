// world_sim: steps a scenario's world and publishes every robot's sensors and the ground truth
// over DDS (see docs/dds.md: topics and lockstep).
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>

#include "common/app.h"
#include "common/config/scenario_flags.h"
#include "common/dds/participant.h"
#include "common/dds/process_exit.h"
#include "common/logging.h"
#include "world_sim/node/sim_node.h"

namespace mrslam::world_sim {
namespace {

struct SimFlags {
  common::CommonFlags common;
  int steps = -1;
  std::string agents = "all";
  int truth_readers = 0;
};

void AddFlags(CLI::App& app, SimFlags* flags) {
  common::AddCommonFlags(app, &flags->common);
  app.add_option("--steps", flags->steps, "Number of steps (overrides run.steps)")->check(CLI::Range(1, 10000000));
  app.add_option("--wait-readers", flags->truth_readers,
                 "Before step 1, wait until this many readers (the evaluator) match the truth topic")
      ->check(CLI::Range(0, 1000));
  app.add_option("--agents", flags->agents,
                 "Comma-separated agents in the lockstep barrier: 'all' (default) or 'none'");
}

// The robots in the lockstep barrier, from --agents.
std::vector<std::string> BarrierAgents(const common::ScenarioOptions& scenario, const std::string& agents) {
  std::vector<std::string> ids;
  if (agents == "all") {
    for (const auto& r : scenario.robots) ids.push_back(r.id);
  } else if (agents != "none") {
    std::stringstream ss(agents);
    for (std::string id; std::getline(ss, id, ',');) {
      if (scenario.RobotIndex(id) < 0) throw std::runtime_error("--agents: unknown robot id '" + id + "'");
      ids.push_back(id);
    }
  }
  return ids;
}

int Run(SimFlags flags) {
  common::SetupLogging("world_sim", flags.common.log_level);
  if (flags.steps >= 0) flags.common.overrides.push_back("run.steps=" + std::to_string(flags.steps));
  const auto scenario = common::LoadScenarioFromFlags(flags.common);
  SimNodeOptions options;
  options.domain = mrslam::dds::ResolveDomain(scenario.run.domain, flags.common.domain);
  options.shared_memory = flags.common.shared_memory;
  options.truth_readers = flags.truth_readers;
  options.agents = BarrierAgents(scenario, flags.agents);
  options.security_dir = flags.common.security_dir;
  const auto& stop = common::InstallStopHandler();
  SimNode node(scenario, options);
  if (!node.Run(stop)) {
    spdlog::warn("stopped before the end of the run");
    return 130;
  }
  return 0;
}

}  // namespace
}  // namespace mrslam::world_sim

int main(int argc, char** argv) {
  using namespace mrslam;
  world_sim::SimFlags flags;
  mrslam::dds::ExitProcess(common::RunMain(
      "world_sim", "mrslam world simulator: publishes each robot's lidar, IMU and odometry, and the truth", argc, argv,
      [&](CLI::App& app) { world_sim::AddFlags(app, &flags); },
      [&](const CLI::App&) { return world_sim::Run(flags); }));
}
