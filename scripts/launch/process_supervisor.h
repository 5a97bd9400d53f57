#pragma once

#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

// Starting, watching and stopping the processes of one run.
namespace mrslam::launch {

// How a child process ended.
struct ChildExit {
  std::string name;
  pid_t pid = -1;
  int exit_code = 0;  // the process's exit code, or 128 + signal when a signal ended it
  int signal = 0;     // the signal that ended it, 0 if it exited
  std::string log_path;
  long peak_rss_kib = 0;  // the most memory it held (getrusage's ru_maxrss), 0 if not known

  bool ok() const { return signal == 0 && exit_code == 0; }
  // "exited with code 3" or "was killed by signal 9 (Killed)".
  std::string Describe() const;
};

// Owns the child processes of one run. Every child is started with fork/exec into one process
// group of its own (so the launcher's terminal signals reach only the launcher, and the whole run
// can be signalled at once), with stdout and stderr in a log file, stdin from /dev/null, no
// inherited descriptors, and a parent-death signal (SIGTERM), so a child cannot outlive the
// launcher even when the launcher is killed. The destructor stops (SIGTERM, then SIGKILL after
// 2 s) and reaps whatever still runs.
// Not thread-safe: use it from one thread (the one that will outlive the children).
class ProcessSupervisor {
 public:
  ProcessSupervisor() = default;
  ~ProcessSupervisor();
  ProcessSupervisor(const ProcessSupervisor&) = delete;
  ProcessSupervisor& operator=(const ProcessSupervisor&) = delete;

  // Starts argv[0] (an absolute path) with argv. Throws std::runtime_error when the executable
  // is missing or the process cannot be created.
  pid_t Start(const std::string& name, const std::vector<std::string>& argv, const std::string& log_path);

  // Starts again, with the same command, a child that has ended and been reaped; its output is
  // appended to the same log. Throws std::runtime_error when no such child has ended or the
  // process cannot be created.
  pid_t Restart(const std::string& name);

  // Reaps the children that have ended since the last call (without blocking), in pid order.
  std::vector<ChildExit> Reap();

  // Number of children started and not yet reaped.
  int running() const;
  // Names of the children still running.
  std::vector<std::string> RunningNames() const;
  // The children's process group (0 before the first Start).
  pid_t process_group() const { return group_; }

  // Sends SIGTERM to the group, waits up to grace for every child to end, then SIGKILLs the
  // group and reaps everything. Returns how the children ended (those reaped here).
  std::vector<ChildExit> StopAll(std::chrono::milliseconds grace);

 private:
  struct Child {
    std::string name;
    pid_t pid = -1;
    std::string log_path;
    bool reaped = false;
    std::vector<std::string> argv;
  };
  pid_t Launch(const std::string& name, const std::vector<std::string>& argv, const std::string& log_path,
               int log_flags);
  static ChildExit ToExit(const Child& child, int status);

  std::vector<Child> children_;
  pid_t group_ = 0;
};

// The last max_lines lines of a text file (empty if it cannot be read).
std::string TailOfFile(const std::string& path, int max_lines);

// Directory of the running executable (from /proc/self/exe).
std::string ExecutableDir();

}  // namespace mrslam::launch
