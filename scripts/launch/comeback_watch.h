#pragma once

#include <chrono>
#include <map>
#include <string>
#include <vector>

#include "scripts/launch/progress_monitor.h"

namespace mrslam::launch {

// Follows the agents the launcher restarted until each is back: its estimates have reached the
// newest step the simulator has published. Records how long each took (docs/faults.md).
class ComebackWatch {
 public:
  using Clock = std::chrono::steady_clock;

  // A robot that is back: the step it reached and the seconds since its restart.
  struct Comeback {
    std::string robot_id;
    int step = 0;
    double seconds = 0.0;
  };

  // The agent of robot_id was restarted at `at`.
  void Restarted(const std::string& robot_id, Clock::time_point at);
  // The robots back since the last call, given the run's progress now.
  std::vector<Comeback> Update(const Progress& progress, Clock::time_point now);
  // The seconds each robot took to come back, restart after restart.
  const std::map<std::string, std::vector<double>>& seconds() const { return seconds_; }

 private:
  std::map<std::string, Clock::time_point> pending_;
  std::map<std::string, std::vector<double>> seconds_;
};

}  // namespace mrslam::launch
