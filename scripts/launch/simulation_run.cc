#include "scripts/launch/simulation_run.h"

namespace mrslam::launch {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

std::vector<std::string> ChildCommand(const RunArgs& run, const std::string& executable,
                                      const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {
      ExecutableDir() + "/" + executable, "--scenario", run.scenario_path,       "--domain",
      std::to_string(run.domain),         "--seed",     std::to_string(run.seed)};
  for (const auto& o : run.overrides) argv.insert(argv.end(), {"--set", o});
  if (run.shared_memory) argv.emplace_back("--shm");
  if (!run.log_level.empty()) argv.insert(argv.end(), {"--log-level", run.log_level});
  if (!run.security_dir.empty()) argv.insert(argv.end(), {"--security", run.security_dir});
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

void StartSimulation(ProcessSupervisor* children, const RunArgs& run, const std::vector<std::string>& robot_ids,
                     int estimate_readers, int truth_readers, const std::string& log_prefix) {
  for (const auto& id : robot_ids) {
    const std::string name = "robot_agent_" + id;
    std::vector<std::string> extra = {"--robot", id, "--wait-readers", std::to_string(estimate_readers)};
    if (run.allow_rejected) extra.emplace_back("--allow-rejected");
    children->Start(name, ChildCommand(run, "robot_agent", extra), log_prefix + name + ".log");
  }
  children->Start("world_sim", ChildCommand(run, "world_sim", {"--wait-readers", std::to_string(truth_readers)}),
                  log_prefix + "world_sim.log");
}

RunEnd SuperviseRun(ProcessSupervisor* children, const RunLimits& limits, const std::atomic<bool>& stop,
                    const std::function<void()>& tick) {
  std::optional<Clock::time_point> world_done_at;
  while (true) {
    if (stop) return {RunEnd::Kind::kStopped, std::nullopt};
    std::optional<ChildExit> failure;
    for (auto& e : children->Reap()) {
      if (!e.ok() && !failure) failure = e;
      if (e.ok() && e.name == "world_sim") world_done_at = Clock::now();
    }
    if (failure) return {RunEnd::Kind::kFailed, failure};
    if (children->running() == 0) return {};
    const auto now = Clock::now();
    if (limits.timeout_s > 0 && now - limits.start > std::chrono::duration<double>(limits.timeout_s))
      return {RunEnd::Kind::kTimedOut, std::nullopt};
    if (world_done_at && now - *world_done_at > limits.drain_timeout) {
      return {RunEnd::Kind::kDrainTimedOut, std::nullopt};
    }
    tick();
  }
}

}  // namespace mrslam::launch
