#pragma once

#include <chrono>
#include <cstdint>
#include <optional>

// When, in realtime, an agent applies the peer messages of the step it has just processed
// (docs/cooperation.md). Pure.
namespace mrslam::robot_agent {

// Halfway from the start of the step just processed to the expected start of the next (by the
// interval between the last two steps' starts). At the start of the next step, a peer's map
// merged there (a large merge takes tens of times an ordinary step) delayed that step's
// estimate; halfway, it delays none of the agent's estimates, and what a peer writes right after
// its own estimate of the step is in by then.
class BetweenSteps {
 public:
  using Clock = std::chrono::steady_clock;

  // Step `step` started at t (its data were all in).
  void Started(std::uint32_t step, Clock::time_point t) {
    interval_.reset();
    if (last_start_ && step == last_step_ + 1) interval_ = t - *last_start_;
    last_start_ = t;
    last_step_ = step;
  }
  // When the peer messages of the last step started are due; nothing before two steps in a row.
  std::optional<Clock::time_point> Due() const {
    if (!interval_ || !last_start_) return std::nullopt;
    return *last_start_ + *interval_ / 2;
  }

 private:
  std::optional<Clock::time_point> last_start_;
  std::uint32_t last_step_ = 0;
  std::optional<Clock::duration> interval_;
};

}  // namespace mrslam::robot_agent
