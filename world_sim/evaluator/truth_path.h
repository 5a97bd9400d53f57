#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "common/se2.h"

namespace mrslam::evaluator {

// A robot's true pose by step, kept for scoring its final trajectory (which arrives at the end of
// the run): dense by step, 24 bytes a step and nothing per entry beside it, its room reserved
// for the run at the start (up to kReservedSteps) so that it never holds two copies while it
// grows. Steps beyond the run's last are not kept, so a forged step cannot make it grow. Pure.
class TruthPath {
 public:
  static constexpr std::uint32_t kReservedSteps = 1U << 20;

  void SetLastStep(std::uint32_t last_step) {
    last_step_ = last_step;
    poses_.reserve(std::size_t{std::min(last_step, kReservedSteps)} + 1);
  }

  void Set(std::uint32_t step, const common::Pose2& pose) {
    if (step > last_step_) return;
    if (step >= poses_.size()) poses_.resize(std::size_t{step} + 1, Missing());
    poses_[step] = pose;
  }

  // The pose at the step, or nullptr if none was set (or it was not finite).
  const common::Pose2* Find(std::uint32_t step) const {
    if (step >= poses_.size() || !std::isfinite(poses_[step].x)) return nullptr;
    return &poses_[step];
  }

 private:
  static common::Pose2 Missing() {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan};
  }

  std::uint32_t last_step_ = 0;
  std::vector<common::Pose2> poses_;
};

}  // namespace mrslam::evaluator
