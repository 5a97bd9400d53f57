#pragma once

#include <vector>

#include <Eigen/Core>

#include "common/config/scenario_options.h"
#include "common/rng.h"
#include "common/se2.h"

namespace mrslam::world_sim {

// One simulated landmark: its options (id and motion model), its true pose and its own random
// stream for process noise. Advances itself one step at a time.
//   static:            never moves, no noise;
//   unicycle:          pose = UnicycleStep(pose, v, w, dt) + N(0, diag(q)) on (x, y, heading);
//   cardinal:          p += speed * dt * (cos h, sin h) + N(0, diag(q_x, q_y)), h one of the
//                      four cardinal directions; after every reverse_every_steps-th step h += pi;
//   constant_velocity: p += velocity * dt + N(0, diag(q_x, q_y)); heading unchanged.
class SimLandmark {
 public:
  // The stream is derived from (seed, "landmark/<id>").
  SimLandmark(const common::LandmarkOptions& options, std::uint64_t seed);

  void Step(double dt_s, const Eigen::Vector3d& process_var);

  int id() const { return options_.id; }
  const common::Pose2& pose() const { return pose_; }
  // True for every model but static (the truth flag).
  bool moving() const { return options_.motion.model != common::LandmarkMotionModel::kStatic; }

 private:
  common::LandmarkOptions options_;
  common::Pose2 pose_;
  common::Rng rng_;
  int steps_taken_ = 0;
};

}  // namespace mrslam::world_sim
