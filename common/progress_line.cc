#include "common/progress_line.h"

#include <unistd.h>

#include <iostream>

namespace mrslam::common {

ProgressLine::ProgressLine() : tty_(isatty(STDERR_FILENO) == 1) {}

ProgressLine::~ProgressLine() { Finish(); }

bool ProgressLine::Show(const std::string& line, bool force) {
  const auto now = std::chrono::steady_clock::now();
  const auto period = tty_ ? std::chrono::milliseconds(250) : std::chrono::milliseconds(2000);
  if (!force && shown_ && now - last_ < period) return false;
  if (tty_) {
    std::cerr << "\r\033[K" << line << std::flush;
    open_ = true;
  } else {
    std::cerr << line << "\n" << std::flush;
  }
  last_ = now;
  shown_ = true;
  return true;
}

void ProgressLine::Finish() {
  if (open_) std::cerr << "\n" << std::flush;
  open_ = false;
}

}  // namespace mrslam::common
