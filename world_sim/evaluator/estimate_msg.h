#pragma once

#include "mrslam.h"
#include "world_sim/evaluator/robot_estimate.h"

// The conversion of an agent's estimate message at the evaluator's and the viewer's edge.
namespace mrslam::evaluator {

// The estimate as the evaluator scores it and the viewer shows it: the confirmed landmarks
// (tentative ones left out), with their covariance and motion.
RobotEstimate FromEstimateMsg(const msg::Estimate& m);

}  // namespace mrslam::evaluator
