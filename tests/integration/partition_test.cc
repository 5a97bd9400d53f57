// Network partitions (docs/faults.md, "Partitions"): the run's processes in network namespaces
// joined by veth pairs, links cut and healed while a run goes on. Needs root; skipped with the
// reason where namespaces cannot be made. The cuts' lengths here are the suite's short versions;
// scripts/partitions.sh runs the 5 s and 40 s realtime cuts (MRSLAM_PARTITION_CUT_S,
// MRSLAM_PARTITION_STEPS, MRSLAM_PARTITION_FACTOR).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/integration/child_process.h"
#include "tests/integration/namespace_network.h"

namespace mrslam {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
using testing::ChildProcess;
using testing::NamespaceNetwork;
using testing::ReadFile;
using Clock = std::chrono::steady_clock;

// This test's own DDS domains.
constexpr int kRealtimeDomain = 105;
constexpr int kShortCutDomain = 106;
constexpr int kLongCutDomain = 107;

constexpr double kDtS = 0.65;  // paper_two_robots' step

double EnvOr(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::stod(v) : fallback;
}

// One run's processes, each in a namespace of the network, on one domain.
class NamespacedRun {
 public:
  NamespacedRun(const NamespaceNetwork& net, std::string dir, int domain, const std::vector<std::string>& overrides)
      : net_(net), dir_(std::move(dir)) {
    std::filesystem::create_directories(dir_);
    common_ = {"--scenario", testing::SourcePath("config/paper_two_robots.yaml"), "--domain", std::to_string(domain)};
    for (const auto& o : overrides) common_.insert(common_.end(), {"--set", o});
  }

  // The evaluator and the agents first (each robot in its namespace), then world_sim.
  void Start(const std::string& sim_ns, const std::string& evaluator_ns, const std::string& r1_ns,
             const std::string& r2_ns) {
    evaluator_ = Spawn(evaluator_ns, "evaluator", {"--out", dir_ + "/out"}, "evaluator");
    r1_ = Spawn(r1_ns, "robot_agent", {"--robot", "r1", "--wait-readers", "1"}, "r1");
    r2_ = Spawn(r2_ns, "robot_agent", {"--robot", "r2", "--wait-readers", "1"}, "r2");
    sim_ = Spawn(sim_ns, "world_sim", {"--wait-readers", "1"}, "world_sim");
  }

  // Waits until world_sim's log holds `text`; false after the timeout or if world_sim ended.
  bool WaitForSimLog(const std::string& text, seconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (ReadFile(Log("world_sim")).find(text) != std::string::npos) return true;
      if (sim_->WaitExit(milliseconds(0))) return false;
      std::this_thread::sleep_for(milliseconds(2));
    }
    return false;
  }

  ChildProcess& sim() { return *sim_; }
  ChildProcess& evaluator() { return *evaluator_; }
  ChildProcess& r1() { return *r1_; }
  ChildProcess& r2() { return *r2_; }
  std::string Log(const std::string& name) const { return dir_ + "/" + name + ".log"; }
  std::string Out(const std::string& file) const { return dir_ + "/out/" + file; }

 private:
  std::unique_ptr<ChildProcess> Spawn(const std::string& ns, const std::string& bin,
                                      const std::vector<std::string>& extra, const std::string& name) {
    std::vector<std::string> argv = {testing::BinPath(bin)};
    argv.insert(argv.end(), common_.begin(), common_.end());
    argv.insert(argv.end(), extra.begin(), extra.end());
    return std::make_unique<ChildProcess>(net_.In(ns, argv), Log(name));
  }

  const NamespaceNetwork& net_;
  std::string dir_;
  std::vector<std::string> common_;
  std::unique_ptr<ChildProcess> sim_, evaluator_, r1_, r2_;
};

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

// The step number logged after the last occurrence of `prefix` (then, for a rendezvous, after
// " at step "); -1 if none.
double LastStepAfter(const std::string& log, const std::string& prefix) {
  const auto at = log.rfind(prefix);
  if (at == std::string::npos) return -1;
  const auto step = log.find_first_of("0123456789", log.find("step ", at) + 5);
  return std::stod(log.substr(step));
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

#define SKIP_WITHOUT_NAMESPACES()                                                \
  do {                                                                           \
    if (const std::string why = NamespaceNetwork::Unavailable(); !why.empty()) { \
      GTEST_SKIP() << "partition tests skipped: " << why;                        \
    }                                                                            \
  } while (false)

// (a) Realtime: r1 and r2 each in a namespace of their own, both linked to world_sim's; the link
// between them is cut for longer than run.ack_timeout_s. Both keep estimating through the cut
// (every step scored), and after it they meet again: a rendezvous of a step after the cut.
TEST(PartitionTest, AgentsCutFromEachOtherKeepEstimatingAndExchangeAgainAfterTheCut) {
  SKIP_WITHOUT_NAMESPACES();
  unsetenv("MRSLAM_DOMAIN");
  const double cut_s = EnvOr("MRSLAM_PARTITION_CUT_S", 5.0);
  const int steps = static_cast<int>(EnvOr("MRSLAM_PARTITION_STEPS", 100));
  const double factor = EnvOr("MRSLAM_PARTITION_FACTOR", 2.0);
  const testing::TempDir temp("mrslam-partition-rt");
  NamespaceNetwork net({"sim", "g1", "g2"});
  ASSERT_TRUE(net.Link("sim", "g1") && net.Link("sim", "g2") && net.Link("g1", "g2"));
  NamespacedRun run(net, temp.path(), kRealtimeDomain,
                    {"run.mode=realtime", "run.realtime_factor=" + std::to_string(factor),
                     "run.steps=" + std::to_string(steps), "run.ack_timeout_s=3", "filter.particles=200"});
  run.Start("sim", "sim", "g1", "g2");
  ASSERT_TRUE(run.WaitForSimLog("all agents ready", seconds(60))) << ReadFile(run.Log("world_sim"));
  const auto t0 = Clock::now();
  // The cut starts at about step 30, before the robots' first encounter (about step 42).
  std::this_thread::sleep_until(t0 + std::chrono::duration<double>(30 * kDtS / factor));
  ASSERT_TRUE(net.Cut("g1", "g2"));
  std::this_thread::sleep_for(std::chrono::duration<double>(cut_s));
  ASSERT_TRUE(net.Heal("g1", "g2"));
  const double healed_step = std::chrono::duration<double>(Clock::now() - t0).count() * factor / kDtS;

  const auto run_s = seconds(static_cast<int>(steps * kDtS / factor) + 60);
  EXPECT_EQ(run.sim().WaitExit(run_s), std::optional<int>(0)) << ReadFile(run.Log("world_sim"));
  EXPECT_EQ(run.r1().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(run.Log("r1"));
  EXPECT_EQ(run.r2().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(run.Log("r2"));
  ASSERT_EQ(run.evaluator().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(run.Log("evaluator"));
  const auto summary = ReadJson(run.Out("summary.json"));
  for (const char* id : {"r1", "r2"}) {
    EXPECT_EQ(summary["robots"][id]["steps_scored"].get<int>(), steps) << id;
    // A rendezvous needs the peer's measurements, a joint transform its snapshot: both came after the cut.
    const std::string log = ReadFile(run.Log(id));
    const double rendezvous = LastStepAfter(log, "rendezvous with ");
    const double joint = LastStepAfter(log, "joint transform from both histories at step ");
    EXPECT_GT(rendezvous, healed_step) << log;
    EXPECT_GT(joint, healed_step) << log;
    std::cout << "partition: " << id << ", cut " << cut_s << " s from step ~30 to step ~" << healed_step
              << " (realtime factor " << factor << ", " << steps << " steps): last rendezvous at step " << rendezvous
              << ", last joint transform at step " << joint << ", stale peer messages rejected "
              << Count(log, "rejected (stale): peer message") << ", peer messages applied a step late "
              << summary["robots"][id]["peer_messages_late"].get<int>() << "\n";
  }
}

// (b) Lockstep, world_sim in a namespace, the agents and the evaluator in another: a cut shorter
// than run.ack_timeout_s delays the run and changes none of its numbers.
TEST(PartitionTest, ACutShorterThanTheAckTimeoutGivesTheSameResults) {
  SKIP_WITHOUT_NAMESPACES();
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp("mrslam-partition-short");
  NamespaceNetwork net({"sim", "agents"});
  ASSERT_TRUE(net.Link("sim", "agents"));
  const std::vector<std::string> overrides = {"run.ack_timeout_s=8"};
  NamespacedRun reference(net, temp.path() + "/reference", kShortCutDomain, overrides);
  reference.Start("sim", "agents", "agents", "agents");
  EXPECT_EQ(reference.sim().WaitExit(seconds(120)), std::optional<int>(0)) << ReadFile(reference.Log("world_sim"));
  EXPECT_EQ(reference.r1().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(reference.Log("r1"));
  EXPECT_EQ(reference.r2().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(reference.Log("r2"));
  ASSERT_EQ(reference.evaluator().WaitExit(seconds(60)), std::optional<int>(0)) << ReadFile(reference.Log("evaluator"));

  NamespacedRun cut(net, temp.path() + "/cut", kShortCutDomain, overrides);
  cut.Start("sim", "agents", "agents", "agents");
  ASSERT_TRUE(cut.WaitForSimLog("step 10/100", seconds(60))) << ReadFile(cut.Log("world_sim"));
  ASSERT_TRUE(net.Cut("sim", "agents"));
  std::this_thread::sleep_for(seconds(2));
  ASSERT_TRUE(net.Heal("sim", "agents"));
  EXPECT_EQ(cut.sim().WaitExit(seconds(120)), std::optional<int>(0)) << ReadFile(cut.Log("world_sim"));
  EXPECT_EQ(cut.r1().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(cut.Log("r1"));
  EXPECT_EQ(cut.r2().WaitExit(seconds(30)), std::optional<int>(0)) << ReadFile(cut.Log("r2"));
  ASSERT_EQ(cut.evaluator().WaitExit(seconds(60)), std::optional<int>(0)) << ReadFile(cut.Log("evaluator"));
  const std::string metrics = ReadFile(cut.Out("metrics.csv"));
  EXPECT_GT(std::count(metrics.begin(), metrics.end(), '\n'), 200);
  EXPECT_TRUE(metrics == ReadFile(reference.Out("metrics.csv"))) << "metrics.csv differs after a 2 s cut";
  for (const char* f : {"trajectories/r1_estimate.tum", "trajectories/r2_estimate.tum"}) {
    EXPECT_TRUE(ReadFile(cut.Out(f)) == ReadFile(reference.Out(f))) << f << " differs after a 2 s cut";
  }
}

// (b) A cut longer than run.ack_timeout_s: every process of the run ends, each with a message
// that says why, the evaluator (on the agents' side, cut from world_sim) included.
TEST(PartitionTest, ACutLongerThanTheAckTimeoutEndsEveryProcessWithAClearMessage) {
  SKIP_WITHOUT_NAMESPACES();
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp("mrslam-partition-long");
  NamespaceNetwork net({"sim", "agents"});
  ASSERT_TRUE(net.Link("sim", "agents"));
  constexpr int kAckTimeoutS = 3;
  NamespacedRun run(net, temp.path(), kLongCutDomain, {"run.ack_timeout_s=" + std::to_string(kAckTimeoutS)});
  run.Start("sim", "agents", "agents", "agents");
  ASSERT_TRUE(run.WaitForSimLog("step 10/100", seconds(60))) << ReadFile(run.Log("world_sim"));
  ASSERT_TRUE(net.Cut("sim", "agents"));
  const auto cut_at = Clock::now();
  // world_sim and the agents give up after the ack timeout, the evaluator after twice that.
  const auto bound = seconds(4 * kAckTimeoutS + 10);
  EXPECT_EQ(run.sim().WaitExit(bound), std::optional<int>(1));
  EXPECT_EQ(run.r1().WaitExit(bound), std::optional<int>(1));
  EXPECT_EQ(run.r2().WaitExit(bound), std::optional<int>(1));
  EXPECT_EQ(run.evaluator().WaitExit(bound), std::optional<int>(1));
  const double ended_s = std::chrono::duration<double>(Clock::now() - cut_at).count();
  EXPECT_LT(ended_s, 4 * kAckTimeoutS + 10);
  EXPECT_NE(ReadFile(run.Log("world_sim")).find("did not acknowledge step"), std::string::npos)
      << ReadFile(run.Log("world_sim"));
  for (const char* agent : {"r1", "r2"}) {
    EXPECT_NE(ReadFile(run.Log(agent)).find("no complete step"), std::string::npos) << ReadFile(run.Log(agent));
  }
  EXPECT_NE(ReadFile(run.Log("evaluator")).find("the run is gone"), std::string::npos)
      << ReadFile(run.Log("evaluator"));
}

}  // namespace
}  // namespace mrslam
