#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/sensor_types.h"
#include "world_sim/evaluator/robot_scorer.h"

namespace mrslam::batch {

// mrslam_batch's default mode: the accuracy of each robot's own filter over the seeds, in-process
// (the scenario's step source and one filter per robot, no DDS), each robot scored as the
// evaluator scores it (evaluator::RobotScorer). With Estimators::kReference, the approximately
// ideal filter (the oracle BatchSmoother: batch MAP with oracle association and kinematics; with
// a landmark_field, of its static landmarks) replaces each robot's own filter on the same data;
// with kJointReference, the causal joint oracle (joint_oracle.h: each robot's reference over its
// own data and what its contacts handed over); with kJointGraphReference, the same bookkeeping with
// the agents' joint graph as the solver (joint_graph_oracle.h; poses only, no map). Prints the
// median and 90th percentile over the seeds per robot and metric; the JSON (json_path, if any)
// also holds every seed's values.
enum class Estimators { kOwnFilter, kReference, kJointReference, kJointGraphReference };

// Sees robot `robot`'s every step: what it sensed and how its estimate scored.
using StepObserver =
    std::function<void(std::size_t robot, const common::SensorStep& step, const evaluator::StepScore& score)>;

// Runs one seed in-process: the scenario's step source (the simulated World, or the replay of a
// recorded data set) and every robot's estimator (its own filter, its oracle reference, or the
// joint oracle's), each scored as the evaluator scores it (evaluator::RobotScorer); observer, if
// any, sees every scored step's score. Returns each robot's summary, in scenario order.
// every: the estimates are scored at every every-th step and the last only (the figures are then
// over those steps; a reference is solved at those steps only, its data added at every step);
// the odometry between them reaches the scorer whole.
std::vector<evaluator::RobotSummary> ScoreSeed(common::ScenarioOptions options, std::uint64_t seed,
                                               Estimators estimators, const StepObserver& observer = {}, int every = 1);

int PrintFilterAccuracy(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                        const std::string& json_path, Estimators estimators, int every = 1);

}  // namespace mrslam::batch
