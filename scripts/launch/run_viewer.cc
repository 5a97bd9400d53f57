#include "scripts/launch/run_viewer.h"

#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <thread>

namespace mrslam::launch {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kJoinTimeout = std::chrono::seconds(20);
constexpr auto kStopGrace = std::chrono::seconds(5);

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

RunViewer::RunViewer(const RunArgs& run, int port, const std::string& log_path) : log_path_(log_path) {
  process_.Start("mrslam_view", ChildCommand(run, "mrslam_view", {"--port", std::to_string(port)}), log_path);
}

RunViewer::~RunViewer() { process_.StopAll(kStopGrace); }

int RunViewer::Join(ProgressMonitor* monitor, const std::atomic<bool>& stop) {
  const auto deadline = Clock::now() + kJoinTimeout;
  while (monitor != nullptr && !monitor->HasSeenParticipant("mrslam_view") && Clock::now() < deadline && !stop) {
    if (!process_.Reap().empty()) break;  // it ended (a port in use, say)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const std::string address = ViewerAddress(ReadText(log_path_));
  if (monitor == nullptr || !monitor->HasSeenParticipant("mrslam_view") || address.empty()) {
    std::cerr << "mrslam_launch: warning: the live view did not start; the run goes on without it; log: " << log_path_
              << "\n";
    return 0;
  }
  std::cerr << "mrslam_launch: live view at " << address << "\n";
  return 1;
}

std::string ViewerAddress(const std::string& log_text) {
  static const std::regex kAddress(R"(serving (http://127\.0\.0\.1:[0-9]+/))");
  std::smatch match;
  return std::regex_search(log_text, match, kAddress) ? match[1].str() : std::string();
}

}  // namespace mrslam::launch
