#pragma once

#include <chrono>
#include <string>

namespace mrslam::common {

// A progress line on stderr for long runs: rewritten in place on a terminal (at most 4 times a
// second), else written as a new line at most every 2 s, so that a log file or a CI log gets a
// readable line now and then instead of every update run together by carriage returns. Not
// thread-safe: callers from several threads hold a lock around Show.
class ProgressLine {
 public:
  ProgressLine();
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  // Shows `line` if the last one shown is old enough, or if `force` (e.g. the last update of a
  // run); returns whether it did.
  bool Show(const std::string& line, bool force = false);
  bool tty() const { return tty_; }
  // Ends an in-place line so that what follows starts on its own line.
  void Finish();

 private:
  bool tty_;
  bool open_ = false;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace mrslam::common
