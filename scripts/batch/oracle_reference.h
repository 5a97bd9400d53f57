#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "robot_agent/smoother/batch_smoother.h"

// The approximately ideal reference against which the agents are judged: the batch MAP smoother
// given the scenario's oracle knowledge, which no agent has: which landmark each detection is
// (the detections must carry identities) and each landmark's true kinematics (static, or
// unicycle with its (v, w)); a replayed data set's landmarks are all static.
namespace mrslam::batch {

using robot_agent::smoother::BatchSmoother;

// The scenario's landmark kinematics by identity. Throws std::invalid_argument for a
// landmark_field or landmark models other than static and unicycle.
std::map<int, BatchSmoother::Kinematics> OracleKinematics(const common::ScenarioOptions& scenario);

// The robots of the set (scenario indices): the first at its known first pose in its own frame,
// the others from first_pose_guesses (one per further robot, in the first robot's frame: any
// guess within the solver's reach, only the data decide the result).
std::vector<BatchSmoother::RobotStart> OracleStarts(const common::ScenarioOptions& scenario,
                                                    const std::vector<int>& robot_indices,
                                                    const std::vector<common::Pose2>& first_pose_guesses);

// Robot j's first pose in robot i's frame G_i as the joint references start it: the truth
// displaced by (0.3 m, 0.3 m, 5 deg), so that a result near that displacement would say the data
// do not place it. frames: the truth's (common::GroundTruth::frames, scenario order).
common::Pose2 FirstPoseGuess(const common::ScenarioOptions& scenario,
                             const std::vector<std::pair<std::string, common::Pose2>>& frames, int i, int j);

// The reference of several robots at once (the first anchors the frame) or, with one index and
// no guesses, of one robot in its own frame. Detections of each other count from step
// robot_detections_from_step on.
BatchSmoother OracleSmoother(const common::ScenarioOptions& scenario, const std::vector<int>& robot_indices,
                             const std::vector<common::Pose2>& first_pose_guesses = {},
                             int robot_detections_from_step = 0);

// With a landmark_field: its static landmarks, all of them static (the movers shuttle back and
// forth, a motion the reference does not model); nothing without a field.
std::optional<std::map<int, BatchSmoother::Kinematics>> FieldStatics(const common::ScenarioOptions& scenario);

// The reference of the robots (as OracleSmoother), or with field_statics (from FieldStatics) the
// reference that knows the field's static landmarks only and leaves the movers' readings out.
std::unique_ptr<BatchSmoother> MakeOracleReference(
    const common::ScenarioOptions& scenario,
    const std::optional<std::map<int, BatchSmoother::Kinematics>>& field_statics, const std::vector<int>& robot_indices,
    const std::vector<common::Pose2>& first_pose_guesses, int robot_detections_from_step);

}  // namespace mrslam::batch
