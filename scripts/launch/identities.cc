#include "scripts/launch/identities.h"

#include <chrono>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <thread>

#include "scripts/launch/process_supervisor.h"

namespace mrslam::launch {

namespace {
constexpr auto kTimeout = std::chrono::seconds(120);
constexpr auto kStopGrace = std::chrono::seconds(2);
}  // namespace

bool MakeIdentities(const std::string& dir, const std::vector<std::string>& names, const std::atomic<bool>& stop) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace);
  std::vector<std::string> argv = {"/bin/bash", ExecutableDir() + "/make_identities.sh", dir};
  argv.insert(argv.end(), names.begin(), names.end());
  const std::string log = dir + "/make_identities.log";
  ProcessSupervisor script;
  script.Start("make_identities.sh", argv, log);
  const auto deadline = std::chrono::steady_clock::now() + kTimeout;
  std::optional<ChildExit> result;
  while (!result) {
    for (auto& e : script.Reap()) result = e;
    if (result) break;
    if (stop || std::chrono::steady_clock::now() > deadline) {
      script.StopAll(kStopGrace);
      if (stop) return false;
      throw std::runtime_error("make_identities.sh did not finish within 120 s; log: " + log);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!result->ok()) {
    throw std::runtime_error("cannot make the run's identities: " + TailOfFile(log, 1) + " (log: " + log + ")");
  }
  return true;
}

}  // namespace mrslam::launch
