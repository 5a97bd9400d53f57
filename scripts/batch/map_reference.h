#pragma once

#include <map>
#include <vector>

#include <Eigen/Core>

#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "common/sensor_types.h"

namespace mrslam::batch {

// The approximately ideal filter against which one robot's own filter is judged (mrslam_batch
// --reference): at every step, the maximum a posteriori estimate of the robot's whole path and
// every seen landmark's path so far, from all the odometry and detections so far, with oracle
// knowledge a filter does not have: which landmark each detection is (the detections must carry
// identities) and each landmark's true kinematics (static or unicycle with its (v, w)). The
// models are the simulator's: x_t = f(x_{t-1}, u_t) + N(0, diag(noise.robot_process_var)),
// l_t = f(l_{t-1}; v, w) + N(0, diag(noise.landmark_process_var)) (static: l_t = l_{t-1}),
// z = (|l - x|, atan2(l - x) - heading) + N(0, diag(sd_r^2, sd_b^2)), f the unicycle step; the
// robot's first pose is known. Solved by Gauss-Newton with Levenberg damping on the sparse
// normal equations, warm-started from the previous step's solution. A landmark's heading is
// started at its second sighting from the displacement between the two sightings.
// Pure; not thread-safe.
class MapReference {
 public:
  // Throws std::invalid_argument for landmark models other than static and unicycle.
  MapReference(const common::ScenarioOptions& options, int robot_index);

  void Process(const common::SensorStep& step);
  const common::Pose2& Pose() const { return path_.back(); }
  // The current position of every landmark seen so far, with its identity.
  std::vector<std::pair<Eigen::Vector2d, int>> Landmarks() const;

 private:
  struct Kinematics {
    bool is_static = true;
    double v_mps = 0.0, w_radps = 0.0;
  };
  struct Chain {  // one landmark's states from its first sighting on
    int first_step = 0;
    Kinematics kinematics;
    std::vector<common::Pose2> states;
    int sightings = 0;
  };
  struct Reading {
    int step, landmark_id;
    double range_m, bearing_rad;
  };

  common::Pose2 StepRobot(const common::Pose2& x, int t) const;  // f(x_{t-1}, u_t)
  common::Pose2 StepLandmark(const common::Pose2& l, const Kinematics& k) const;
  void Solve();

  double dt_s_;
  Eigen::Vector3d robot_var_, landmark_var_;
  double var_r_, var_b_;
  std::map<int, Kinematics> kinematics_;                        // by landmark id
  std::vector<common::Pose2> path_;                             // path_[0]: the known start
  std::vector<std::vector<common::OdometrySegment>> odometry_;  // odometry_[t - 1]: step t's commands
  std::map<int, Chain> chains_;
  std::vector<Reading> readings_;
};

}  // namespace mrslam::batch
