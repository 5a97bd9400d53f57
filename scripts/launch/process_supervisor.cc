#include "scripts/launch/process_supervisor.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <fstream>
#include <stdexcept>
#include <thread>

namespace mrslam::launch {

namespace {

// Closes every descriptor from 3 up (async-signal-safe: only system calls).
void CloseInheritedDescriptors() {
#ifdef SYS_close_range
  if (syscall(SYS_close_range, 3U, ~0U, 0U) == 0) return;
#endif
  const long max_fd = sysconf(_SC_OPEN_MAX);
  for (long fd = 3; fd < (max_fd > 0 ? max_fd : 4096); ++fd) close(static_cast<int>(fd));
}

void WriteAll(int fd, const char* text) {
  std::size_t left = std::strlen(text);
  while (left > 0) {
    const ssize_t n = write(fd, text, left);
    if (n <= 0) return;
    text += n;
    left -= static_cast<std::size_t>(n);
  }
}

}  // namespace

std::string ChildExit::Describe() const {
  if (signal != 0) {
    const char* what = strsignal(signal);
    return "was killed by signal " + std::to_string(signal) + (what != nullptr ? " (" + std::string(what) + ")" : "");
  }
  return "exited with code " + std::to_string(exit_code);
}

ProcessSupervisor::~ProcessSupervisor() {
  if (running() > 0) StopAll(std::chrono::seconds(2));
}

pid_t ProcessSupervisor::Start(const std::string& name, const std::vector<std::string>& argv,
                               const std::string& log_path) {
  return Launch(name, argv, log_path, O_TRUNC);
}

pid_t ProcessSupervisor::Restart(const std::string& name) {
  for (auto it = children_.rbegin(); it != children_.rend(); ++it) {
    if (it->name != name) continue;
    if (!it->reaped) throw std::runtime_error("cannot restart " + name + ": it is still running");
    const Child ended = *it;  // Launch appends to children_
    return Launch(ended.name, ended.argv, ended.log_path, O_APPEND);
  }
  throw std::runtime_error("cannot restart " + name + ": no such process was started");
}

pid_t ProcessSupervisor::Launch(const std::string& name, const std::vector<std::string>& argv,
                                const std::string& log_path, int log_flags) {
  if (argv.empty() || access(argv[0].c_str(), X_OK) != 0) {
    throw std::runtime_error("cannot run '" + (argv.empty() ? std::string() : argv[0]) + "' (" +
                             (argv.empty() ? "no command" : std::strerror(errno)) + ")");
  }
  const int log_fd = open(log_path.c_str(), O_WRONLY | O_CREAT | log_flags | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error("cannot write '" + log_path + "': " + std::strerror(errno));
  const int null_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
  // Everything the child needs is prepared before fork: after it only system calls are safe.
  std::vector<char*> args;
  args.reserve(argv.size() + 1);
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t group = group_;

  const pid_t pid = fork();
  if (pid < 0) {
    const int err = errno;
    close(log_fd);
    if (null_fd >= 0) close(null_fd);
    throw std::runtime_error("cannot start " + name + ": fork failed: " + std::strerror(err));
  }
  if (pid == 0) {
    setpgid(0, group);  // group 0: become the leader of a new group
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(129);  // the launcher died before prctl took effect
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    dup2(log_fd, 1);
    dup2(log_fd, 2);
    if (null_fd >= 0) dup2(null_fd, 0);
    CloseInheritedDescriptors();
    execv(args[0], args.data());
    WriteAll(2, "mrslam_launch: error: exec failed: ");
    WriteAll(2, std::strerror(errno));
    WriteAll(2, "\n");
    _exit(127);
  }
  close(log_fd);
  if (null_fd >= 0) close(null_fd);
  // Also set the group from the parent, so it holds before either side runs on.
  if (group_ == 0) group_ = pid;
  setpgid(pid, group_);  // may fail harmlessly once the child has exec'ed (it did it itself)
  children_.push_back({name, pid, log_path, false, argv});
  return pid;
}

ChildExit ProcessSupervisor::ToExit(const Child& child, int status) {
  ChildExit e;
  e.name = child.name;
  e.pid = child.pid;
  e.log_path = child.log_path;
  if (WIFSIGNALED(status)) {
    e.signal = WTERMSIG(status);
    e.exit_code = 128 + e.signal;
  } else {
    e.exit_code = WEXITSTATUS(status);
  }
  return e;
}

std::vector<ChildExit> ProcessSupervisor::Reap() {
  std::vector<ChildExit> ended;
  for (auto& child : children_) {
    if (child.reaped) continue;
    int status = 0;
    rusage usage{};
    const pid_t r = wait4(child.pid, &status, WNOHANG, &usage);
    if (r == child.pid) {
      child.reaped = true;
      ended.push_back(ToExit(child, status));
      ended.back().peak_rss_kib = usage.ru_maxrss;
    } else if (r < 0 && errno == ECHILD) {
      child.reaped = true;  // someone else reaped it: treat it as lost
      ChildExit e{child.name, child.pid, 1, 0, child.log_path};
      ended.push_back(e);
    }
  }
  return ended;
}

int ProcessSupervisor::running() const {
  int n = 0;
  for (const auto& child : children_) n += child.reaped ? 0 : 1;
  return n;
}

std::vector<std::string> ProcessSupervisor::RunningNames() const {
  std::vector<std::string> names;
  for (const auto& child : children_) {
    if (!child.reaped) names.push_back(child.name);
  }
  return names;
}

std::vector<ChildExit> ProcessSupervisor::StopAll(std::chrono::milliseconds grace) {
  std::vector<ChildExit> ended;
  if (running() == 0) return ended;
  if (group_ > 0) killpg(group_, SIGTERM);
  // Also signal each child by pid, in case one left the group.
  for (const auto& child : children_) {
    if (!child.reaped) kill(child.pid, SIGTERM);
  }
  const auto deadline = std::chrono::steady_clock::now() + grace;
  while (running() > 0 && std::chrono::steady_clock::now() < deadline) {
    for (auto& e : Reap()) ended.push_back(std::move(e));
    if (running() > 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (running() > 0) {
    if (group_ > 0) killpg(group_, SIGKILL);
    for (auto& child : children_) {
      if (child.reaped) continue;
      kill(child.pid, SIGKILL);
      int status = 0;
      rusage usage{};
      while (wait4(child.pid, &status, 0, &usage) < 0 && errno == EINTR) {
      }
      child.reaped = true;
      ended.push_back(ToExit(child, status));
      ended.back().peak_rss_kib = usage.ru_maxrss;
    }
  }
  return ended;
}

std::string TailOfFile(const std::string& path, int max_lines) {
  std::ifstream in(path);
  if (!in) return {};
  std::deque<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(line);
    if (static_cast<int>(lines.size()) > max_lines) lines.pop_front();
  }
  std::string out;
  for (const auto& line : lines) out += line + "\n";
  return out;
}

std::string ExecutableDir() {
  char buffer[4096];
  const ssize_t n = readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (n <= 0) return ".";
  std::string path(buffer, static_cast<std::size_t>(n));
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

}  // namespace mrslam::launch
