#pragma once

#include <string>

#include "common/config/scenario_options.h"

namespace mrslam::batch {

// mrslam_batch --held DIR: the joint estimate over the raw measurements each agent of a run held
// at its end (DIR/<robot>.factors, written by robot_agent --factors-out), solved as the agent
// solves it (cooperation/joint_estimate.h), each robot's path scored against the truth of the
// run (the scenario and seed the run had) in its own frame at its keyframes; with `union_all`,
// each robot's over the union of every agent's logs instead. Prints per robot the position and
// heading RMSE, the robots placed and the CPU time of the solve; `json_path` gets the same.
int PrintHeldReference(const common::ScenarioOptions& options, const std::string& dir, bool union_all,
                       const std::string& json_path);

}  // namespace mrslam::batch
