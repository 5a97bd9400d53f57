#pragma once

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "tests/test_paths.h"

extern char** environ;

namespace mrslam::testing {

// A child process for multi-process tests: started with posix_spawn, its stdout and stderr in a
// log file; waited for with a timeout; killed (SIGKILL) if still running when destroyed, so a
// failing test leaves no process behind.
class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const std::string& log_path) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~ChildProcess() {
    if (running()) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }
  bool running() const { return pid_ > 0 && !exit_code_.has_value(); }
  pid_t pid() const { return pid_; }
  void Signal(int signal) const {
    if (running()) kill(pid_, signal);
  }

  // The exit code (128 + signal if killed), or nullopt if still running after the timeout.
  std::optional<int> WaitExit(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running()) {
      int status = 0;
      const pid_t r = waitpid(pid_, &status, WNOHANG);
      if (r == pid_) {
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return exit_code_;
  }

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
};

// Reads a whole text file (empty if missing).
std::string ReadFile(const std::string& path);

// Starts build/bin/<executable> with args, its output in log_path.
inline std::unique_ptr<ChildProcess> StartBin(const std::string& executable, std::vector<std::string> args,
                                              const std::string& log_path) {
  args.insert(args.begin(), BinPath(executable));
  return std::make_unique<ChildProcess>(args, log_path);
}

// Starts one robot_agent per robot id with the shared args; logs in dir/<id>.log.
inline std::vector<std::unique_ptr<ChildProcess>> StartAgents(const std::vector<std::string>& robot_ids,
                                                              const std::vector<std::string>& args,
                                                              const std::string& dir) {
  std::vector<std::unique_ptr<ChildProcess>> agents;
  for (const auto& id : robot_ids) {
    auto agent_args = args;
    agent_args.insert(agent_args.end(), {"--robot", id});
    std::string log = dir;
    log.append("/").append(id).append(".log");
    agents.push_back(StartBin("robot_agent", agent_args, log));
  }
  return agents;
}

// Expects the process to exit with code 1 after printing exactly one line that holds `what`.
inline void ExpectOneLineError(ChildProcess& process, const std::string& log_path, const std::string& what) {
  const auto code = process.WaitExit(std::chrono::seconds(20));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1);
  const std::string log = ReadFile(log_path);
  EXPECT_NE(log.find(what), std::string::npos) << log;
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
}

// A fresh temporary directory /tmp/<prefix>-XXXXXX for a test's logs and outputs. Declared before
// the test's processes, it outlives them; it is removed with its contents when the test ends
// without a failure, and kept (its path printed) for its logs when the test failed.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// The children of a process (from /proc), with their command lines.
std::map<pid_t, std::string> ChildrenOf(pid_t parent);

// Waits until the process has at least `count` children that have started their own program (or
// the timeout) and returns those.
std::map<pid_t, std::string> WaitForChildren(pid_t parent, std::size_t count, std::chrono::milliseconds timeout);

// The first of the processes whose command line holds every one of `parts`; 0 if none.
pid_t FindProcess(const std::map<pid_t, std::string>& processes, const std::vector<std::string>& parts);

// The process groups of the processes.
std::set<pid_t> GroupsOf(const std::map<pid_t, std::string>& processes);

// True when neither the processes nor any member of their process groups still exist.
::testing::AssertionResult NoneLeft(const std::map<pid_t, std::string>& processes, const std::set<pid_t>& groups);

}  // namespace mrslam::testing
