#pragma once

#include <map>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/cooperation/factor_exchange.h"
#include "scripts/batch/information_sets.h"

namespace mrslam::batch {

// The causal joint graph reference (mrslam_batch --reference --joint --graph): the causal joint
// oracle's bookkeeping (InformationSets: after each step what each robot holds of every robot's
// data, handed over at contacts, transitively) with the agents' own joint estimate as the solver.
// When asked at a step, robot i's estimate is the joint graph (cooperation::SolveJoint: keyframes,
// each robot's odometry correction estimated, robots placed by their mutual detections; docs/
// smoother.md, "The joint graph") over exactly the data it holds then, solved to convergence, its
// landmark readings labelled by the identities the lidar reports (the oracle's association; the
// scenario must report them; its landmarks must be static, as the joint graph's are). Where the oracle smoother's model
// of the odometry is not the real robot's (a data set's replay), this is the reference the agents' joint estimate can
// be held to. Each solve starts cold: the estimate at a step is a function of the data held then only.
class JointGraphOracle {
 public:
  explicit JointGraphOracle(const common::ScenarioOptions& scenario);

  // The team's next step (steps[i]: robot i's): the contacts and every robot's data; with solve,
  // each robot's joint graph solved.
  void Process(const std::vector<common::SensorStep>& steps, bool solve);
  // Robot i's pose at the last step solved, in its own frame (its start until then).
  const common::Pose2& Pose(int i) const { return poses_.at(i); }

 private:
  // Robot i's joint graph over what it holds after step k.
  common::Pose2 Solve(int i, int k) const;

  common::ScenarioOptions scenario_;
  std::vector<std::string> ids_;
  InformationSets sets_;
  std::vector<robot_agent::cooperation::FactorLog> data_;  // each robot's steps so far, labelled
  std::vector<common::Pose2> poses_;
};

}  // namespace mrslam::batch
