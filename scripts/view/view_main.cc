// mrslam_view: a live view of a run in the browser (one more DDS reader in the run's domain),
// or the replay of a finished run's folder (--run DIR). See docs/viewer.md.
#include <chrono>
#include <iostream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "common/app.h"
#include "common/config/scenario_flags.h"
#include "common/dds/participant.h"
#include "common/dds/process_exit.h"
#include "scripts/view/frame_hub.h"
#include "scripts/view/live_feed.h"
#include "scripts/view/replay_run.h"
#include "scripts/view/view_server.h"
#include "world_sim/evaluator/view_steps.h"

namespace mrslam::view {
namespace {

constexpr char kName[] = "mrslam_view";
constexpr int kDefaultPort = 8765;
// The feed builds a frame at most once per period, and each client gets one at most as often.
constexpr auto kFramePeriod = std::chrono::milliseconds(100);

struct ViewFlags {
  common::CommonFlags common;
  int port = kDefaultPort;
  std::string run_dir;
};

// Starts serving and prints the address (once the viewer is seen in a DDS domain, its address
// is in its output).
void StartAndAnnounce(ViewServer* server, int port, const std::string& what) {
  const int bound = server->Start(port);
  std::cout << kName << ": serving http://127.0.0.1:" << bound << "/ (" << what << ")" << std::endl;
}

void WaitForStopSignal() {
  const auto& stop = common::InstallStopHandler();
  while (!stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

int Replay(const ViewFlags& flags) {
  ReplayRun run = LoadReplayRun(flags.run_dir);
  const nlohmann::json info = {
      {"mode", "replay"}, {"header", nlohmann::json::parse(run.header_json)}, {"dir", flags.run_dir}};
  ViewServer server({info.dump(), nullptr, std::move(run.steps_json)}, kFramePeriod);
  StartAndAnnounce(&server, flags.port, "replay of " + flags.run_dir + ", " + std::to_string(run.steps) + " steps");
  WaitForStopSignal();
  server.Stop();
  return 0;
}

int Live(const ViewFlags& flags) {
  if (flags.common.scenario.empty()) throw std::runtime_error("give --scenario FILE (live) or --run DIR (replay)");
  const auto scenario = common::LoadScenarioFromFlags(flags.common);
  const int domain = dds::ResolveDomain(scenario.run.domain, flags.common.domain);
  const nlohmann::json info = {{"mode", "live"}, {"header", evaluator::ViewHeader(scenario)}, {"domain", domain}};
  FrameHub hub;
  ViewServer server({info.dump(), &hub, ""}, kFramePeriod);
  StartAndAnnounce(&server, flags.port, "scenario '" + scenario.name + "', DDS domain " + std::to_string(domain));
  // The participant is named mrslam_view (the launcher waits to see it); under DDS-Security its
  // identity is "viewer".
  LiveFeed feed(scenario, {domain, "mrslam_view", flags.common.shared_memory, flags.common.security_dir, "viewer"},
                &hub, kFramePeriod);
  WaitForStopSignal();
  feed.Stop();  // the last frame, then the clients' event streams end
  hub.Close();
  server.Stop();
  return 0;
}

void AddFlags(CLI::App& app, ViewFlags* flags) {
  common::AddCommonFlags(app, &flags->common);
  auto* scenario = app.get_option("--scenario");
  scenario->required(false);
  app.add_option("--port", flags->port, "Port on 127.0.0.1 (0: a free one, printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  app.add_option("--run", flags->run_dir, "Replay this finished run's folder (its view.jsonl) instead of a live run")
      ->check(CLI::ExistingDirectory)
      ->excludes(scenario);
}

}  // namespace
}  // namespace mrslam::view

int main(int argc, char** argv) {
  using namespace mrslam;
  view::ViewFlags flags;
  mrslam::dds::ExitProcess(common::RunMain(
      view::kName,
      "mrslam viewer: a live view of a run in the browser (Server-Sent Events from DDS), or --run DIR to replay a "
      "finished run",
      argc, argv, [&](CLI::App& app) { view::AddFlags(app, &flags); },
      [&](const CLI::App&) { return flags.run_dir.empty() ? view::Live(flags) : view::Replay(flags); }));
}
