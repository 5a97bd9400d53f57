// mrslam_launch: runs a scenario end to end as separate processes (evaluator, world_sim, one
// robot_agent per robot) on a free DDS domain, supervises them, shows progress, and at the end
// prints a summary table and writes plots. With --seeds A..B it runs each seed in turn and
// aggregates (median, 90th percentile). See docs/executables.md.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/app.h"
#include "common/config/scenario_flags.h"
#include "common/config/scenario_options.h"
#include "common/cpu_clock.h"
#include "common/dds/discovery_server.h"
#include "common/dds/participant.h"
#include "common/dds/process_exit.h"
#include "common/progress_line.h"
#include "common/seed_range.h"
#include "scripts/launch/comeback_watch.h"
#include "scripts/launch/domain_picker.h"
#include "scripts/launch/identities.h"
#include "scripts/launch/process_supervisor.h"
#include "scripts/launch/progress_monitor.h"
#include "scripts/launch/run_report.h"
#include "scripts/launch/run_viewer.h"
#include "scripts/launch/shm_leftovers.h"
#include "scripts/launch/simulation_run.h"
#include "scripts/launch/wakeup_latency.h"

namespace mrslam::launch {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr char kName[] = "mrslam_launch";
constexpr char kAgentPrefix[] = "robot_agent_";  // the agents' names as children
constexpr auto kStopGrace = std::chrono::seconds(5);
// Once world_sim has finished, the agents and the evaluator must finish within this time.
constexpr auto kDrainTimeout = std::chrono::seconds(120);
constexpr auto kPlotTimeout = std::chrono::seconds(300);
constexpr auto kEvaluatorJoinTimeout = std::chrono::seconds(20);
constexpr int kLogTailLines = 15;
constexpr int kPlotScriptMissingMatplotlib = 3;  // plot_run.py's exit code when it cannot plot

// Outcomes of a run (process exit codes of the launcher).
constexpr int kOk = 0;
constexpr int kFailed = 1;
constexpr int kStopped = 130;
// RunSeed only, never an exit code: the run failed before every robot had published step 1.
constexpr int kFailedBeforeStep1 = -1;

struct LaunchFlags {
  common::CommonFlags common;
  bool log_level_given = false;
  std::string out_dir;
  std::string seeds;  // "A..B"
  bool no_plots = false;
  double timeout_s = 0.0;
  bool allow_rejected = false;
  std::optional<int> view_port;  // --view: serve a live view of each run on this port
  bool secure = false;
  int restarts = 0;               // --restart: how many times a dead agent is started again
  bool low_latency = false;       // --low-latency: CPUs kept from sleeping while the runs last
  bool low_latency_held = false;  // whether the kernel took that request
  bool discovery_server = false;  // --discovery-server: the launcher's participant serves discovery
};

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string FormatSeconds(double s) {
  char buffer[32];
  if (s < 60) {
    std::snprintf(buffer, sizeof(buffer), "%.1f s", s);
  } else {
    std::snprintf(buffer, sizeof(buffer), "%d min %02d s", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  }
  return buffer;
}

// Shows a run's progress (common::ProgressLine); off a terminal only when something changed.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(std::string prefix) : prefix_(std::move(prefix)) {}

  void Show(const Progress& p, int total_steps, double elapsed_s, std::optional<double> left_s) {
    if (!line_.tty() && p.steps_done == last_steps_ && p.rendezvous == last_rendezvous_) return;
    const std::string line = prefix_ + "step " + std::to_string(p.steps_done) + "/" + std::to_string(total_steps) +
                             ", rendezvous so far " + std::to_string(p.rendezvous) + ", elapsed " +
                             FormatSeconds(elapsed_s) + ", time left " +
                             (left_s ? "~" + FormatSeconds(*left_s) : std::string("?"));
    if (!line_.Show(line)) return;
    last_steps_ = p.steps_done;
    last_rendezvous_ = p.rendezvous;
  }
  void Finish() { line_.Finish(); }

 private:
  std::string prefix_;
  common::ProgressLine line_;
  int last_steps_ = -1;
  int last_rendezvous_ = -1;
};

// The flags every child gets: --scenario --domain --seed --set... [--shm] [--log-level] [--security].
RunArgs ChildArgs(const LaunchFlags& flags, const std::string& scenario_path, int domain, long long seed) {
  RunArgs run{scenario_path, domain, seed, flags.common.overrides, flags.common.shared_memory, ""};
  if (flags.log_level_given) run.log_level = flags.common.log_level;
  run.allow_rejected = flags.allow_rejected;
  run.security_dir = flags.common.security_dir;
  return run;
}

void ReportFailure(const ChildExit& failure, const std::string& what_else) {
  std::cerr << kName << ": error: " << failure.name << " (pid " << failure.pid << ") " << failure.Describe()
            << "; log: " << failure.log_path << what_else << "\n";
  const std::string tail = TailOfFile(failure.log_path, kLogTailLines);
  if (!tail.empty()) {
    std::cerr << "---- last lines of " << failure.log_path << " ----\n" << tail << "----\n";
  }
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// Runs plot_run.py on a run's folder. Never fails the run: problems are warnings. Returns the
// plots written.
std::vector<std::string> RunPlots(const std::string& dir, const std::atomic<bool>& stop) {
  const std::string script = ExecutableDir() + "/plot_run.py";
  const std::string python = "/usr/bin/python3";
  if (access(script.c_str(), R_OK) != 0) {
    std::cerr << kName << ": warning: " << script << " not found: no plots\n";
    return {};
  }
  if (access(python.c_str(), X_OK) != 0) {
    std::cerr << kName << ": warning: " << python << " not found (apt-get install python3-matplotlib): no plots\n";
    return {};
  }
  const std::string log = dir + "/logs/plot_run.log";
  ProcessSupervisor plot;
  plot.Start("plot_run", {python, script, dir}, log);
  const auto deadline = Clock::now() + kPlotTimeout;
  std::optional<ChildExit> result;
  while (!result) {
    for (auto& e : plot.Reap()) result = e;
    if (result) break;
    if (stop || Clock::now() > deadline) {
      plot.StopAll(kStopGrace);
      std::cerr << kName << ": warning: plotting " << (stop ? "interrupted" : "timed out") << "\n";
      return {};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (result->signal == 0 && result->exit_code == kPlotScriptMissingMatplotlib) {
    std::cerr << kName << ": warning: " << python
              << " cannot import matplotlib (apt-get install python3-matplotlib): no plots\n";
    return {};
  }
  if (!result->ok()) {
    std::cerr << kName << ": warning: plot_run.py " << result->Describe() << "; log: " << log << "\n"
              << TailOfFile(log, kLogTailLines);
    return {};
  }
  std::vector<std::string> written;
  for (const char* name : {"trajectories.png", "errors.png", "overview.png"}) {
    const std::string path = dir + "/plots/" + name;
    if (fs::exists(path)) written.push_back(path);
  }
  return written;
}

// Stops what still runs of a run that did not end well and says why.
void ReportEnd(const RunEnd& end, const RunLimits& limits, ProcessSupervisor* children, const std::string& dir) {
  const auto others = children->RunningNames();
  if (end.kind == RunEnd::Kind::kStopped) {
    std::cerr << kName << ": interrupted: stopping " << JoinNames(others) << "\n";
    children->StopAll(kStopGrace);
    return;
  }
  children->StopAll(kStopGrace);
  if (end.kind == RunEnd::Kind::kFailed) {
    ReportFailure(*end.failure, others.empty() ? "" : "; stopped " + JoinNames(others));
    return;
  }
  const std::string timeout =
      end.kind == RunEnd::Kind::kTimedOut
          ? "the run did not finish within --timeout-s " + FormatSeconds(limits.timeout_s)
          : "world_sim finished but the others did not within " + FormatSeconds(Seconds(limits.drain_timeout));
  std::cerr << kName << ": error: " << timeout << " (still running: " << JoinNames(others) << "); logs in " << dir
            << "/logs\n";
}

// Once a run's processes are gone: removes what a killed one left in /dev/shm (a clean exit
// leaves nothing there) and says so.
void RemoveShmFiles(int domain) {
  if (const int n = RemoveShmLeftovers(domain); n > 0) {
    std::cerr << kName << ": removed " << n << " file(s) a killed process left in /dev/shm\n";
  }
}

// Starts the evaluator and waits until it is in the domain (the monitor sees it), before the others:
// it is not part of the lockstep barrier, so a short run could otherwise end (and its writers go
// away) before it joins. Returns false, reported, if the evaluator ended first.
bool StartEvaluator(ProcessSupervisor* children, const RunArgs& run, ProgressMonitor* monitor, const std::string& dir,
                    const std::atomic<bool>& stop) {
  children->Start("evaluator", ChildCommand(run, "evaluator", {"--out", dir}), dir + "/logs/evaluator.log");
  if (!monitor) return true;
  const auto deadline = Clock::now() + kEvaluatorJoinTimeout;
  while (!monitor->HasSeenParticipant("evaluator") && Clock::now() < deadline && !stop) {
    const auto ended = children->Reap();
    if (!ended.empty()) {  // the evaluator ended before the run began
      ReportFailure(ended.front(), "");
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (!monitor->HasSeenParticipant("evaluator") && !stop) {
    std::cerr << kName << ": warning: the evaluator has not joined DDS domain " << run.domain << " after "
              << FormatSeconds(Seconds(kEvaluatorJoinTimeout)) << "; starting the others anyway\n";
  }
  return true;
}

// The run's wall time and the CPU time of all its processes (the launcher's included).
struct RunCost {
  double wall_s = 0.0;
  double cpu_s = 0.0;
  std::map<std::string, long> peak_rss_kib;  // by process name
};

// Reads the summary the evaluator wrote into dir, adds the run's cost and DDS domain, and
// writes it back. Returns kOk (and the summary) or kFailed.
// The agents restarted during a run: how often, and how long each took to come back.
struct RestartRecord {
  std::map<std::string, int> restarts;                    // by child name
  std::map<std::string, std::vector<double>> comeback_s;  // by robot id
};

// How the run's processes ran: the CPUs kept awake, discovery through the launcher's server.
struct RunConditions {
  bool low_latency = false;
  bool discovery_server = false;
};

int FinishSummary(const std::string& dir, const RunCost& cost, int domain, const RunConditions& conditions,
                  const RestartRecord& restarted, json* summary_out) {
  const std::string summary_path = dir + "/summary.json";
  std::ifstream in(summary_path);
  if (!in) {
    std::cerr << kName << ": error: every process finished but the evaluator wrote no " << summary_path
              << "; log: " << dir << "/logs/evaluator.log\n";
    return kFailed;
  }
  json summary;
  try {
    in >> summary;
  } catch (const std::exception& e) {
    std::cerr << kName << ": error: " << summary_path << " is not valid JSON (" << e.what() << ")\n";
    return kFailed;
  }
  in.close();
  if (summary.contains("wall_seconds")) summary["evaluator_wall_seconds"] = summary["wall_seconds"];
  summary["wall_seconds"] = cost.wall_s;
  summary["cpu_seconds"] = cost.cpu_s;
  summary["cpu_cores_mean"] = cost.wall_s > 0.0 ? cost.cpu_s / cost.wall_s : 0.0;
  summary["dds_domain"] = domain;
  summary["low_latency"] = conditions.low_latency;
  summary["discovery_server"] = conditions.discovery_server;
  json& peak = summary["peak_rss_mib"] = json::object();
  for (const auto& [name, kib] : cost.peak_rss_kib) peak[name] = static_cast<double>(kib) / 1024.0;
  if (summary.contains("robots") && summary["robots"].is_object()) {
    for (auto& [id, robot] : summary["robots"].items()) {
      const auto it = restarted.restarts.find(kAgentPrefix + id);
      robot["restarts"] = it == restarted.restarts.end() ? 0 : it->second;
      const auto back = restarted.comeback_s.find(id);
      robot["restart_comeback_s"] = back == restarted.comeback_s.end() ? std::vector<double>{} : back->second;
    }
  }
  {
    const std::string tmp = summary_path + ".tmp";
    std::ofstream out(tmp);
    out << summary.dump(2) << "\n";
    out.close();
    if (!out) throw std::runtime_error("cannot write " + summary_path);
    fs::rename(tmp, summary_path);
  }
  *summary_out = summary;
  return kOk;
}

// With --restart: an agent that a signal ended after it had published its estimate of the last
// step has done its part (a crash while it shuts down): it is neither restarted nor a failure,
// and a warning says so. An exit code is never let go (an agent that rejected input ends so).
bool FinishedBeforeItDied(const ChildExit& e, const Progress& progress, int total_steps) {
  const auto it = progress.robot_steps.find(e.name.substr(std::string(kAgentPrefix).size()));
  if (e.signal == 0 || it == progress.robot_steps.end() || it->second < total_steps) return false;
  std::cerr << kName << ": warning: " << e.name << " (pid " << e.pid << ") " << e.Describe()
            << " after it had published its last step; not restarted; log: " << e.log_path << "\n";
  return true;
}

// A folder emptied when made and removed when it goes (nothing for an empty path).
class SnapshotFolder {
 public:
  explicit SnapshotFolder(std::string path) : path_(std::move(path)) { Remove(); }
  ~SnapshotFolder() { Remove(); }
  SnapshotFolder(const SnapshotFolder&) = delete;
  SnapshotFolder& operator=(const SnapshotFolder&) = delete;

 private:
  void Remove() const {
    std::error_code ignored;
    if (!path_.empty()) fs::remove_all(path_, ignored);
  }
  std::string path_;
};

// With --low-latency: the request to the kernel, held until the launcher ends (nullptr without the
// flag). One that the kernel refuses gives a warning and the runs go on without it.
std::unique_ptr<WakeupLatencyRequest> RequestLowLatency(LaunchFlags* flags) {
  if (!flags->low_latency) return nullptr;
  auto request = std::make_unique<WakeupLatencyRequest>(0);
  flags->low_latency_held = request->held();
  if (!request->held()) {
    std::cerr << kName << ": warning: --low-latency: " << request->error() << "; running without it\n";
  }
  return request;
}

// Runs one seed into dir. Returns kOk (and the summary), kFailed or kStopped.
int RunSeed(const LaunchFlags& flags, const common::ScenarioOptions& scenario, const std::string& scenario_path,
            long long seed, int domain, const std::string& dir, const std::string& progress_prefix,
            const std::atomic<bool>& stop, json* summary_out) {
  fs::create_directories(dir + "/logs");
  fs::remove(dir + "/summary.json");  // a stale summary must not pass for this run's
  RunArgs run = ChildArgs(flags, scenario_path, domain, seed);
  // With restarts, the agents' snapshots: fresh for the run, gone after it.
  if (flags.restarts > 0) run.snapshot_dir = dir + "/snapshots";
  const SnapshotFolder snapshots(run.snapshot_dir);
  // With raw measurements shared, what each agent holds at the end.
  if (scenario.cooperation.share_factors) run.factors_dir = dir + "/factors";

  const auto start = Clock::now();
  const double cpu_start = common::ProcessTreeCpuSeconds();
  std::vector<std::string> robot_ids;
  for (const auto& r : scenario.robots) robot_ids.push_back(r.id);
  // The monitor joins first, to see the evaluator join. With --discovery-server it is the run's
  // discovery server, named to the children in their environment: without it they would find no one.
  const std::string server = flags.discovery_server ? DiscoveryServerAddress(domain) : "";
  if (!server.empty()) setenv(dds::kDiscoveryServerVariable, server.c_str(), 1);
  std::unique_ptr<ProgressMonitor> monitor;
  try {
    monitor = std::make_unique<ProgressMonitor>(domain, flags.common.shared_memory, flags.common.security_dir,
                                                robot_ids, server);
  } catch (const std::exception& e) {
    if (!server.empty()) {
      std::cerr << kName << ": error: cannot serve discovery at " << server << " (" << e.what() << ")\n";
      return kFailed;
    }
    std::cerr << kName << ": warning: no progress display (" << e.what() << ")\n";
  }
  ProcessSupervisor children;
  if (!StartEvaluator(&children, run, monitor.get(), dir, stop)) return kFailed;
  std::unique_ptr<RunViewer> viewer;
  int view_readers = 0;
  if (flags.view_port) {
    viewer = std::make_unique<RunViewer>(run, *flags.view_port, dir + "/logs/mrslam_view.log");
    view_readers = viewer->Join(monitor.get(), stop);
  }
  if (stop) {  // interrupted while the evaluator (or the viewer) joined: start nothing more
    std::cerr << kName << ": interrupted: stopping " << JoinNames(children.RunningNames()) << "\n";
    children.StopAll(kStopGrace);
    return kStopped;
  }
  // Then the agents, then the simulator (it waits for every agent's "ready"). The evaluator (and
  // the progress monitor and the viewer) must read every estimate: the agents wait for them.
  StartSimulation(&children, run, robot_ids, (monitor ? 2 : 1) + view_readers, 1 + view_readers, dir + "/logs/");

  ProgressPrinter printer(progress_prefix);
  std::optional<Clock::time_point> first_step_at;
  int steps_seen = 0;  // the run's progress: the step every robot has published
  ComebackWatch comebacks;
  Progress last_progress;
  const int total_steps = scenario.run.steps;
  const auto show_progress = [&] {
    if (monitor) {
      const auto now = Clock::now();
      const Progress p = monitor->Poll();
      steps_seen = p.steps_done;
      last_progress = p;
      for (const auto& back : comebacks.Update(p, now)) {
        printer.Finish();
        std::cerr << kName << ": " << progress_prefix << kAgentPrefix << back.robot_id << " is back at step "
                  << back.step << ", " << FormatSeconds(back.seconds) << " after its restart\n";
      }
      if (p.steps_done > 0 && !first_step_at) first_step_at = now;
      std::optional<double> left;
      if (first_step_at && p.steps_done > 1) {
        const double per_step = Seconds(now - *first_step_at) / (p.steps_done - 1);
        left = per_step * std::max(0, total_steps - p.steps_done);
      }
      printer.Show(p, total_steps, Seconds(now - start), left);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  };
  const RunLimits limits{start, flags.timeout_s, kDrainTimeout};
  RestartPolicy restart{flags.restarts,
                        [&](const ChildExit& e, int n) {
                          printer.Finish();
                          std::cerr << kName << ": " << progress_prefix << e.name << " (pid " << e.pid << ") "
                                    << e.Describe() << " after step " << steps_seen << "; restarting it (restart " << n
                                    << " of " << flags.restarts << "); log: " << e.log_path << "\n";
                          const std::string robot = e.name.substr(std::string(kAgentPrefix).size());
                          if (monitor) monitor->Restarted(robot);
                          comebacks.Restarted(robot, Clock::now());
                        },
                        [&](const ChildExit& e) { return FinishedBeforeItDied(e, last_progress, total_steps); }};
  const RunEnd end = SuperviseRun(&children, limits, stop, show_progress, restart);
  printer.Finish();
  // The children are stopped first: the monitor's participant takes a while to leave a large run.
  if (end.kind != RunEnd::Kind::kDone) ReportEnd(end, limits, &children, dir);
  const bool monitor_joined = monitor != nullptr;
  monitor.reset();
  if (run.shared_memory) RemoveShmFiles(domain);
  if (end.kind != RunEnd::Kind::kDone) {
    if (end.kind == RunEnd::Kind::kStopped) return kStopped;
    return monitor_joined && !first_step_at ? kFailedBeforeStep1 : kFailed;
  }
  const RunCost cost{Seconds(Clock::now() - start), common::ProcessTreeCpuSeconds() - cpu_start, end.peak_rss_kib};
  return FinishSummary(dir, cost, domain, {flags.low_latency_held, flags.discovery_server},
                       {end.restarts, comebacks.seconds()}, summary_out);
}

// What a finished seed prints: one line in a multi-seed run, else the summary table, the outputs
// and the plots.
void PrintRun(const common::ScenarioOptions& scenario, long long seed, const json& summary, const std::string& dir,
              const std::vector<std::string>& plots, bool multi) {
  const double wall_s = summary.value("wall_seconds", 0.0);
  if (multi) {
    std::cout << "seed " << seed << ": finished in " << FormatSeconds(wall_s) << " (" << dir << ")\n" << std::flush;
    return;
  }
  std::cout << "\nScenario '" << scenario.name << "', seed " << seed << ", " << summary.value("steps", json()).dump()
            << " steps, finished in " << FormatSeconds(wall_s) << "\n\n"
            << SummaryTable(summary) << "\n"
            << "Outputs: " << dir << "/summary.json, " << dir << "/metrics.csv, " << dir << "/trajectories/, " << dir
            << "/logs/\n";
  if (!plots.empty()) {
    std::cout << "Plots:\n";
    for (const auto& p : plots) std::cout << "  " << p << "\n";
  }
  std::cout << std::flush;
}

// Writes and prints the aggregate over the seeds that finished; kFailed if any seed failed.
int WriteAggregate(const common::ScenarioOptions& scenario, const std::vector<long long>& seeds,
                   const std::vector<json>& summaries, const std::vector<long long>& finished,
                   const std::vector<long long>& failed, const std::string& out_dir) {
  json aggregate = Aggregate(summaries, finished);
  aggregate["failed_seeds"] = failed;
  const std::string path = out_dir + "/aggregate.json";
  std::ofstream out(path);
  out << aggregate.dump(2) << "\n";
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path);
  std::cout << "\nScenario '" << scenario.name << "', seeds " << seeds.front() << ".." << seeds.back() << " ("
            << finished.size() << " runs): median and 90th percentile over seeds\n\n"
            << AggregateTable(aggregate) << "\nAggregate: " << path << "\n"
            << std::flush;
  if (failed.empty()) return kOk;
  std::string list;
  for (const long long seed : failed) list += (list.empty() ? "" : ", ") + std::to_string(seed);
  std::cerr << kName << ": error: " << failed.size() << " of " << seeds.size() << " seeds failed (" << list
            << "; logs in " << out_dir << "/seed-<S>/logs)\n";
  return kFailed;
}

// The flags of the run's processes: with --secure, --security names the identities made for the
// scenario's processes into OUT/security. Nullopt if stopped while making them.
std::optional<LaunchFlags> SecureFlags(LaunchFlags flags, const common::ScenarioOptions& scenario,
                                       const std::string& out_dir, const std::atomic<bool>& stop) {
  if (!flags.secure) return flags;
  std::vector<std::string> names = {"world_sim", "evaluator", "monitor", "viewer"};
  for (const auto& r : scenario.robots) names.push_back(r.id);
  flags.common.security_dir = out_dir + "/security";
  if (!MakeIdentities(flags.common.security_dir, names, stop)) return std::nullopt;
  return flags;
}

int Main(LaunchFlags flags) {
  const auto scenario = common::LoadScenarioFromFlags(flags.common);  // validates; throws one line
  const std::string scenario_path = fs::absolute(flags.common.scenario).string();
  if (!flags.seeds.empty() && flags.common.seed >= 0) throw std::runtime_error("give --seed or --seeds, not both");
  if (flags.secure && !flags.common.security_dir.empty())
    throw std::runtime_error("give --secure or --security, not both");
  if (flags.discovery_server && (flags.secure || !flags.common.security_dir.empty()))
    throw std::runtime_error(
        "--discovery-server does not work with DDS-Security (--secure, --security): Fast DDS 2.9.1's server aborts "
        "with security on");
  if (!flags.common.security_dir.empty()) flags.common.security_dir = fs::absolute(flags.common.security_dir).string();
  const std::vector<long long> seeds = flags.seeds.empty()
                                           ? std::vector<long long>{static_cast<long long>(scenario.seed)}
                                           : common::ParseSeedRange("--seeds", flags.seeds).Seeds();
  const bool multi = !flags.seeds.empty();

  // The domain: --domain or MRSLAM_DOMAIN if given (as every process resolves it), else a free one.
  const char* env_domain = std::getenv("MRSLAM_DOMAIN");
  const bool domain_given = flags.common.domain >= 0 || (env_domain != nullptr && *env_domain != '\0');
  const int given_domain = domain_given ? dds::ResolveDomain(scenario.run.domain, flags.common.domain) : -1;

  const std::string out_dir = fs::absolute(flags.out_dir).lexically_normal().string();
  fs::create_directories(out_dir);
  const auto& stop = common::InstallStopHandler();
  const std::unique_ptr<WakeupLatencyRequest> wakeup = RequestLowLatency(&flags);
  const std::optional<LaunchFlags> run_flags = SecureFlags(flags, scenario, out_dir, stop);
  if (!run_flags) return kStopped;

  // A seed that fails does not end a multi-seed run: the others go on, the aggregate is over the
  // seeds that finished and names the failed ones, and the exit code says that one failed.
  std::vector<json> summaries;
  std::vector<long long> finished, failed;
  for (const long long seed : seeds) {
    // Held until this seed's processes are gone, so that no other run on the host takes it.
    DomainReservation held;
    if (!domain_given) held = PickFreeDomain(getpid());
    const int domain = domain_given ? given_domain : held.domain();
    if (domain < 0) {
      throw std::runtime_error("no free DDS domain in " + std::to_string(kFirstAutoDomain) + ".." +
                               std::to_string(kLastAutoDomain) + " (give one with --domain)");
    }
    const std::string dir = multi ? out_dir + "/seed-" + std::to_string(seed) : out_dir;
    std::cerr << kName << ": scenario '" << scenario.name << "', seed " << seed << ", " << scenario.run.steps
              << " steps, " << scenario.robots.size() << " robots, DDS domain " << domain << "; logs in " << dir
              << "/logs\n";
    json summary;
    const std::string prefix = multi ? "[seed " + std::to_string(seed) + "] " : "";
    const auto run_seed = [&] {
      return RunSeed(*run_flags, scenario, scenario_path, seed, domain, dir, prefix, stop, &summary);
    };
    int code = run_seed();
    // Fast DDS 2.9.1 leaves about one secure start in 20 with a pair of participants whose
    // handshake never completes (docs/security.md): such a start is tried once more.
    if (code == kFailedBeforeStep1 && !run_flags->common.security_dir.empty()) {
      std::cerr << kName << ": " << prefix << "the processes did not all authenticate each other; starting seed "
                << seed << " once more\n";
      code = run_seed();
    }
    if (code == kFailedBeforeStep1) code = kFailed;
    if (code == kFailed && multi) {
      failed.push_back(seed);
      std::cerr << kName << ": seed " << seed << " failed; going on with the next seeds\n";
      continue;
    }
    if (code != kOk) return code;
    for (const auto& warning : RejectionWarnings(summary, dir + "/logs")) {
      std::cerr << kName << ": " << prefix << warning << "\n";
    }

    std::vector<std::string> plots;
    if (!flags.no_plots) plots = RunPlots(dir, stop);
    if (stop) return kStopped;
    PrintRun(scenario, seed, summary, dir, plots, multi);
    summaries.push_back(std::move(summary));
    finished.push_back(seed);
  }

  if (multi) return WriteAggregate(scenario, seeds, summaries, finished, failed, out_dir);
  return kOk;
}

}  // namespace
}  // namespace mrslam::launch

namespace mrslam::launch {
namespace {

void AddFlags(CLI::App& app, LaunchFlags* flags) {
  common::AddCommonFlags(app, &flags->common);
  app.add_option("--out", flags->out_dir, "Output folder (summary.json, metrics.csv, trajectories/, plots/, logs/)")
      ->required();
  app.add_option("--seeds", flags->seeds, "Run seeds A..B in turn into OUT/seed-<S>/ and write OUT/aggregate.json");
  app.add_flag("--no-plots", flags->no_plots, "Do not run plot_run.py");
  app.add_flag("--allow-rejected", flags->allow_rejected,
               "Let a run pass although an agent rejected malformed, foreign-writer, contested or beyond-horizon "
               "input (stale and duplicate input never fails a run)");
  app.add_option("--timeout-s", flags->timeout_s, "Stop a run that takes longer than this (0: no limit)")
      ->check(common::FiniteNonNegative());
  app.add_option("--view", flags->view_port,
                 "Serve a live view of the run on http://127.0.0.1:PORT/ (mrslam_view; default port 8765, 0: a "
                 "free one, printed)")
      ->expected(0, 1)
      ->default_str("8765")
      ->check(CLI::Range(0, 65535));
  app.add_option(
         "--restart", flags->restarts,
         "Start a robot_agent that dies (a signal or a non-zero exit) again with the same command, up to N "
         "times per agent; it restores its latest snapshot (every run.snapshot_every_steps steps) and rejoins the "
         "run (docs/faults.md). 0: a dead agent fails the run")
      ->check(CLI::Range(0, 1000));
  app.add_flag("--low-latency", flags->low_latency,
               "Ask the kernel to keep the CPUs from sleeping while the runs last (/dev/cpu_dma_latency, root only): "
               "a DDS sample then wakes its reader sooner; idle CPUs poll instead of halting. Without "
               "permission, a warning and the runs go on without it");
  app.add_flag("--discovery-server", flags->discovery_server,
               "Discovery through a server in the launcher instead of every process announcing itself to every "
               "other: each process learns only of the participants and endpoints that share its topics (cheaper "
               "for large teams; data still flows directly; docs/dds.md)");
  app.add_flag("--secure", flags->secure,
               "DDS-Security on: make identities for the run's processes into OUT/security and pass --security to "
               "every process (docs/security.md)");
}

}  // namespace
}  // namespace mrslam::launch

int main(int argc, char** argv) {
  using namespace mrslam;
  launch::LaunchFlags flags;
  mrslam::dds::ExitProcess(common::RunMain(
      launch::kName,
      "mrslam launcher: runs a scenario end to end (evaluator, world_sim, one robot_agent per robot) as separate "
      "processes on a free DDS domain, then prints a summary and writes plots",
      argc, argv, [&](CLI::App& app) { launch::AddFlags(app, &flags); },
      [&](const CLI::App& app) {
        flags.log_level_given = app.get_option("--log-level")->count() > 0;
        return launch::Main(flags);
      }));
}
