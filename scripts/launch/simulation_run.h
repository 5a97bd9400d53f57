#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "scripts/launch/process_supervisor.h"

// One simulation run as separate processes, as the launcher and mrslam_grid --multi-process run
// it: the command lines, starting world_sim and one robot_agent per robot, and supervising them
// to their end.
namespace mrslam::launch {

// What every process of a run gets: --scenario --domain --seed --set... [--shm] [--log-level]
// [--security].
struct RunArgs {
  std::string scenario_path;
  int domain = 0;
  long long seed = 0;
  std::vector<std::string> overrides;
  bool shared_memory = false;
  std::string log_level;        // empty: each process's default
  bool allow_rejected = false;  // the agents end normally after input that fails a run
  std::string security_dir{};   // DDS-Security with the identities in this folder (empty: off)
  std::string snapshot_dir{};   // the agents' snapshots (robot_agent --snapshot-dir; empty: none)
  std::string factors_dir{};    // the raw measurements each agent holds at the end (--factors-out)
};

// The command line of one of the run's processes: the executable beside this one, the run's
// flags, then extra.
std::vector<std::string> ChildCommand(const RunArgs& run, const std::string& executable,
                                      const std::vector<std::string>& extra);

// Starts one robot_agent per robot (named robot_agent_<id>, each waiting until estimate_readers
// readers match its estimate topic), then world_sim (which waits for every agent's "ready" and
// for truth_readers readers of the truth). Each log is log_prefix + name + ".log".
void StartSimulation(ProcessSupervisor* children, const RunArgs& run, const std::vector<std::string>& robot_ids,
                     int estimate_readers, int truth_readers, const std::string& log_prefix);

// The limits of a run: all of it from start (0: none), and how long the others may take to
// finish once world_sim has.
struct RunLimits {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double timeout_s = 0.0;
  std::chrono::seconds drain_timeout{120};
};

// Which children come back when they die: a robot_agent that ends by a signal or a non-zero exit
// while world_sim still runs is started again with the same command, up to max_restarts times
// per agent; the restarted agent rejoins the run (docs/faults.md).
struct RestartPolicy {
  int max_restarts = 0;  // 0: a dead agent fails the run
  // Told of each restart before it happens: how the agent ended and which restart this is (1..).
  std::function<void(const ChildExit&, int)> on_restart;
  // Asked first about every agent that dies: true if its death is to be let go (neither a restart
  // nor a failure), e.g. a crash after it had published its last step.
  std::function<bool(const ChildExit&)> let_go;
};

// How a supervised run ended. Unless kDone, children may still run: the caller stops them.
struct RunEnd {
  enum class Kind { kDone, kFailed, kTimedOut, kDrainTimedOut, kStopped };
  Kind kind = Kind::kDone;
  std::optional<ChildExit> failure;     // kFailed: the first child that failed
  std::map<std::string, int> restarts;  // by child name, those restarted at least once
  // By child name, the most memory (KiB) it held: of a restarted one, the largest of its lives.
  std::map<std::string, long> peak_rss_kib;
};

// Watches the children until every one has ended, one has failed, a limit has run out or stop
// has been raised, restarting dead agents as the policy says. tick() runs between the checks: the
// caller's reading and progress, which also paces the loop (it should wait a few milliseconds).
RunEnd SuperviseRun(ProcessSupervisor* children, const RunLimits& limits, const std::atomic<bool>& stop,
                    const std::function<void()>& tick, const RestartPolicy& restart = {});

}  // namespace mrslam::launch
