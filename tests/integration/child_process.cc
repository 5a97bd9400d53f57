#include "tests/integration/child_process.h"

#include <dirent.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace mrslam::testing {
namespace {

// A process as /proc/<pid>/stat shows it.
struct ProcInfo {
  pid_t pid = 0;
  pid_t ppid = 0;
  pid_t pgid = 0;
  char state = '?';
};

std::optional<ProcInfo> ReadProc(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text;
  if (!std::getline(in, text)) return std::nullopt;
  const auto close = text.rfind(')');  // the command name may hold spaces and parentheses
  if (close == std::string::npos) return std::nullopt;
  std::istringstream rest(text.substr(close + 1));
  ProcInfo info;
  info.pid = pid;
  rest >> info.state >> info.ppid >> info.pgid;
  return info;
}

std::string CommandLine(pid_t pid) {
  std::string cmd = ReadFile("/proc/" + std::to_string(pid) + "/cmdline");
  for (char& c : cmd) c = c == '\0' ? ' ' : c;
  return cmd;
}

}  // namespace

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TempDir::TempDir(const std::string& prefix) {
  std::string templ = "/tmp/" + prefix + "-XXXXXX";
  if (mkdtemp(templ.data()) == nullptr) {
    ADD_FAILURE() << "cannot create " << templ << ": " << std::strerror(errno);
    return;
  }
  path_ = templ;
}

TempDir::~TempDir() {
  if (path_.empty()) return;
  if (::testing::Test::HasFailure()) {
    std::cerr << "logs kept in " << path_ << "\n";
    return;
  }
  std::error_code error;
  std::filesystem::remove_all(path_, error);
}

std::map<pid_t, std::string> ChildrenOf(pid_t parent) {
  std::map<pid_t, std::string> children;
  DIR* dir = opendir("/proc");
  if (dir == nullptr) return children;
  while (dirent* entry = readdir(dir)) {
    char* end = nullptr;
    const long pid = std::strtol(entry->d_name, &end, 10);
    if (end == entry->d_name || *end != '\0') continue;
    const auto info = ReadProc(static_cast<pid_t>(pid));
    if (info && info->ppid == parent) children[info->pid] = CommandLine(info->pid);
  }
  closedir(dir);
  return children;
}

std::map<pid_t, std::string> WaitForChildren(pid_t parent, std::size_t count, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const std::string parent_command = CommandLine(parent);
  // A child between fork and exec still shows the parent's command line: not counted yet.
  const auto started = [&] {
    auto children = ChildrenOf(parent);
    for (auto it = children.begin(); it != children.end();)
      it = it->second == parent_command ? children.erase(it) : ++it;
    return children;
  };
  auto children = started();
  while (children.size() < count && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    children = started();
  }
  return children;
}

pid_t FindProcess(const std::map<pid_t, std::string>& processes, const std::vector<std::string>& parts) {
  for (const auto& process : processes) {
    const std::string& cmd = process.second;
    if (std::all_of(parts.begin(), parts.end(),
                    [&cmd](const std::string& p) { return cmd.find(p) != std::string::npos; })) {
      return process.first;
    }
  }
  return 0;
}

std::set<pid_t> GroupsOf(const std::map<pid_t, std::string>& processes) {
  std::set<pid_t> groups;
  for (const auto& [pid, cmd] : processes) {
    if (const auto info = ReadProc(pid)) groups.insert(info->pgid);
  }
  return groups;
}

::testing::AssertionResult NoneLeft(const std::map<pid_t, std::string>& processes, const std::set<pid_t>& groups) {
  for (const auto& [pid, cmd] : processes) {
    if (ReadProc(pid)) return ::testing::AssertionFailure() << "process " << pid << " is still there: " << cmd;
  }
  for (const pid_t group : groups) {
    if (kill(-group, 0) == 0 || errno != ESRCH) {
      return ::testing::AssertionFailure() << "process group " << group << " still has members";
    }
  }
  return ::testing::AssertionSuccess();
}

}  // namespace mrslam::testing
