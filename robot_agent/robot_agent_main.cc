// robot_agent: one robot's SLAM filter in its own process and frame (docs/design.md).
#include <spdlog/spdlog.h>

#include "common/app.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_flags.h"
#include "common/dds/participant.h"
#include "common/logging.h"
#include "robot_agent/filters/filter_factory.h"
#include "robot_agent/node/agent_node.h"

int main(int argc, char** argv) {
  using namespace mrslam;
  CLI::App app{"mrslam robot agent: runs one robot's SLAM filter on its own sensor topics"};
  common::CommonFlags flags;
  common::AddCommonFlags(app, &flags);
  std::string robot_id;
  std::string filter;
  int particles = -1;
  int estimate_readers = 0;
  app.add_option("--robot", robot_id, "Robot id from the scenario (e.g. r1)")->required();
  app.add_option("--filter", filter, "fastslam, ekf or ekf_ela (overrides filter.type)");
  app.add_option("--particles", particles, "Number of particles (overrides filter.particles)");
  app.add_option("--wait-readers", estimate_readers,
                 "Before saying ready, wait until this many readers match the estimate topic");
  return common::RunMain("robot_agent", app, argc, argv, [&] {
    common::SetupLogging("robot_agent/" + robot_id, flags.log_level);
    if (!filter.empty()) flags.overrides.push_back("filter.type=" + filter);
    if (particles >= 0) flags.overrides.push_back("filter.particles=" + std::to_string(particles));
    const auto scenario = common::LoadScenarioFromFlags(flags);
    if (scenario.RobotIndex(robot_id) < 0) {
      throw std::runtime_error("--robot: unknown robot id '" + robot_id + "' (not in scenario '" + scenario.name +
                               "')");
    }
    // The agent's code gets its own options only: never the scenario, which holds the truth.
    const robot_agent::AgentOptions agent = common::AgentOptionsFor(scenario, robot_id);
    auto slam = robot_agent::filters::CreateFilter(agent, scenario.seed);
    if (!slam) throw std::runtime_error("filter '" + agent.filter.type + "' is not available");
    robot_agent::AgentNodeOptions options;
    options.domain = mrslam::dds::ResolveDomain(scenario.run.domain, flags.domain);
    options.shared_memory = flags.shared_memory;
    options.timeout_s = scenario.run.ack_timeout_s;
    options.estimate_readers = estimate_readers;
    const auto& stop = common::InstallStopHandler();
    robot_agent::AgentNode node(agent, options, std::move(slam));
    return node.Run(stop) ? 0 : 130;
  });
}
