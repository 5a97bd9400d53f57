#include "scripts/launch/simulation_run.h"

#include <algorithm>

namespace mrslam::launch {

namespace {
using Clock = std::chrono::steady_clock;

constexpr char kAgentPrefix[] = "robot_agent_";

// Restarts e's child, or lets its death go, if the policy says so; true if it did either.
bool MaybeRestart(ProcessSupervisor* children, const ChildExit& e, bool world_running, const RestartPolicy& policy,
                  std::map<std::string, int>* restarts) {
  if (e.name.rfind(kAgentPrefix, 0) != 0) return false;
  if (policy.max_restarts > 0 && policy.let_go && policy.let_go(e)) return true;
  if (!world_running) return false;
  int& done = (*restarts)[e.name];
  if (done >= policy.max_restarts) {
    if (done == 0) restarts->erase(e.name);
    return false;
  }
  ++done;
  if (policy.on_restart) policy.on_restart(e, done);
  children->Restart(e.name);
  return true;
}

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
    if (!run.snapshot_dir.empty()) extra.insert(extra.end(), {"--snapshot-dir", run.snapshot_dir});
    if (!run.factors_dir.empty()) extra.insert(extra.end(), {"--factors-out", run.factors_dir});
    children->Start(name, ChildCommand(run, "robot_agent", extra), log_prefix + name + ".log");
  }
  children->Start("world_sim", ChildCommand(run, "world_sim", {"--wait-readers", std::to_string(truth_readers)}),
                  log_prefix + "world_sim.log");
}

RunEnd SuperviseRun(ProcessSupervisor* children, const RunLimits& limits, const std::atomic<bool>& stop,
                    const std::function<void()>& tick, const RestartPolicy& restart) {
  std::optional<Clock::time_point> world_done_at;
  std::map<std::string, int> restarts;
  std::map<std::string, long> peak_rss_kib;
  const auto end = [&](RunEnd::Kind kind, std::optional<ChildExit> failure = std::nullopt) {
    return RunEnd{kind, std::move(failure), restarts, peak_rss_kib};
  };
  while (true) {
    if (stop) return end(RunEnd::Kind::kStopped);
    std::optional<ChildExit> failure;
    for (auto& e : children->Reap()) {
      long& peak = peak_rss_kib[e.name];
      peak = std::max(peak, e.peak_rss_kib);
      if (e.ok() && e.name == "world_sim") world_done_at = Clock::now();
      if (e.ok() || failure || MaybeRestart(children, e, !world_done_at, restart, &restarts)) continue;
      failure = e;
    }
    if (failure) return end(RunEnd::Kind::kFailed, failure);
    if (children->running() == 0) return end(RunEnd::Kind::kDone);
    const auto now = Clock::now();
    if (limits.timeout_s > 0 && now - limits.start > std::chrono::duration<double>(limits.timeout_s))
      return end(RunEnd::Kind::kTimedOut);
    if (world_done_at && now - *world_done_at > limits.drain_timeout) return end(RunEnd::Kind::kDrainTimedOut);
    tick();
  }
}

}  // namespace mrslam::launch
