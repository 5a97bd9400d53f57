// robot_agent: one robot's SLAM filter in its own process and frame (docs/design.md).
#include <stdexcept>
#include <string>
#include <utility>

#include <spdlog/spdlog.h>

#include "common/app.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_flags.h"
#include "common/dds/participant.h"
#include "common/dds/process_exit.h"
#include "common/logging.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/node/agent_node.h"

namespace mrslam::robot_agent {
namespace {

struct AgentFlags {
  common::CommonFlags common;
  std::string robot_id;
  std::string filter;
  int particles = -1;
  int estimate_readers = 0;
  bool allow_rejected = false;
  std::string snapshot_dir;
  std::string factors_dir;
};

void AddFlags(CLI::App& app, AgentFlags* flags) {
  common::AddCommonFlags(app, &flags->common);
  app.add_option("--robot", flags->robot_id, "Robot id from the scenario (e.g. r1)")->required();
  app.add_option("--filter", flags->filter, "fastslam, ekf, ekf_ela or smoother (overrides filter.type)")
      ->check(CLI::IsMember({"fastslam", "ekf", "ekf_ela", "smoother"}));
  app.add_option("--particles", flags->particles, "Number of particles (overrides filter.particles)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--wait-readers", flags->estimate_readers,
                 "Before saying ready, wait until this many readers match the estimate topic")
      ->check(CLI::Range(0, 1000));
  app.add_flag("--allow-rejected", flags->allow_rejected,
               "End normally even after malformed, foreign-writer, contested or beyond-horizon input");
  app.add_option("--snapshot-dir", flags->snapshot_dir,
                 "Write the agent's state to DIR/<robot>.snapshot every run.snapshot_every_steps steps and, started "
                 "again in the same run, go on from it");
  app.add_option("--factors-out", flags->factors_dir,
                 "After the last step, write the raw measurements the agent holds (its own and its peers') to "
                 "DIR/<robot>.factors");
}

// What a snapshot must have been written by: the same scenario, seed, robot, estimator and domain.
std::string RunFingerprint(const common::ScenarioOptions& scenario, const AgentOptions& agent, int domain) {
  return "scenario '" + scenario.name + "' seed " + std::to_string(scenario.seed) + " robot " + agent.robot_id +
         " filter " + agent.filter.type + " steps " + std::to_string(scenario.run.steps) + " domain " +
         std::to_string(domain);
}

int Run(AgentFlags flags) {
  common::SetupLogging("robot_agent/" + flags.robot_id, flags.common.log_level);
  if (!flags.filter.empty()) flags.common.overrides.push_back("filter.type=" + flags.filter);
  if (flags.particles >= 0) flags.common.overrides.push_back("filter.particles=" + std::to_string(flags.particles));
  const auto scenario = common::LoadScenarioFromFlags(flags.common);
  if (scenario.RobotIndex(flags.robot_id) < 0) {
    throw std::runtime_error("--robot: unknown robot id '" + flags.robot_id + "' (not in scenario '" + scenario.name +
                             "')");
  }
  // The agent's code gets its own options only: never the scenario, which holds the truth.
  AgentOptions agent = common::AgentOptionsFor(scenario, flags.robot_id);
  // Under DDS-Security a relayed step could not be told to be its origin's: only the own are shared.
  const bool no_relay =
      !flags.common.security_dir.empty() && agent.cooperation.share_factors && agent.cooperation.relay_factors;
  if (no_relay) agent.cooperation.relay_factors = false;
  auto slam = factory::CreateFilter(agent, scenario.seed);
  if (!slam) throw std::runtime_error("filter '" + agent.filter.type + "' is not available");
  AgentNodeOptions options;
  options.domain = mrslam::dds::ResolveDomain(scenario.run.domain, flags.common.domain);
  options.shared_memory = flags.common.shared_memory;
  options.timeout_s = scenario.run.ack_timeout_s;
  options.estimate_readers = flags.estimate_readers;
  options.lockstep = scenario.run.mode == common::RunMode::kLockstep;
  options.horizon_steps = static_cast<std::uint32_t>(scenario.run.horizon_steps);
  options.allow_rejected = flags.allow_rejected;
  options.security_dir = flags.common.security_dir;
  options.history_steps = scenario.run.history_steps;
  options.snapshot_dir = flags.snapshot_dir;
  options.snapshot_every_steps = static_cast<std::uint32_t>(scenario.run.snapshot_every_steps);
  options.run_fingerprint = RunFingerprint(scenario, agent, options.domain);
  options.factors_dir = flags.factors_dir;
  const auto& stop = common::InstallStopHandler();
  AgentNode node(agent, options, std::move(slam));
  if (no_relay) spdlog::info("DDS-Security on: raw measurements are not relayed (cooperation.relay_factors off)");
  return node.Run(stop) ? 0 : 130;
}

}  // namespace
}  // namespace mrslam::robot_agent

int main(int argc, char** argv) {
  using namespace mrslam;
  robot_agent::AgentFlags flags;
  mrslam::dds::ExitProcess(common::RunMain(
      "robot_agent", "mrslam robot agent: runs one robot's SLAM filter on its own sensor topic", argc, argv,
      [&](CLI::App& app) { robot_agent::AddFlags(app, &flags); },
      [&](const CLI::App&) { return robot_agent::Run(flags); }));
}
