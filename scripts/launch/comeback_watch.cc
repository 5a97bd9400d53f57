#include "scripts/launch/comeback_watch.h"

namespace mrslam::launch {

void ComebackWatch::Restarted(const std::string& robot_id, Clock::time_point at) { pending_[robot_id] = at; }

std::vector<ComebackWatch::Comeback> ComebackWatch::Update(const Progress& progress, Clock::time_point now) {
  std::vector<Comeback> back;
  for (auto it = pending_.begin(); it != pending_.end();) {
    const auto step = progress.robot_steps.find(it->first);
    if (step == progress.robot_steps.end() || step->second < 1 || step->second < progress.clock_step) {
      ++it;
      continue;
    }
    const double s = std::chrono::duration<double>(now - it->second).count();
    back.push_back({it->first, step->second, s});
    seconds_[it->first].push_back(s);
    it = pending_.erase(it);
  }
  return back;
}

}  // namespace mrslam::launch
