#include "scripts/batch/joint_graph_oracle.h"

#include <algorithm>
#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>

#include "common/config/agent_options_projection.h"
#include "robot_agent/cooperation/joint_estimate.h"

namespace mrslam::batch {

using robot_agent::cooperation::FactorLog;

JointGraphOracle::JointGraphOracle(const common::ScenarioOptions& scenario)
    : scenario_(scenario), sets_(static_cast<int>(scenario.robots.size())), data_(scenario.robots.size()) {
  if (!scenario.sensors.lidar.report_identity)
    throw std::invalid_argument("the joint graph reference labels readings by the identities the lidar reports");
  const bool movers = (scenario.landmark_field.enabled && scenario.landmark_field.moving_fraction > 0.0) ||
                      std::any_of(scenario.landmarks.begin(), scenario.landmarks.end(),
                                  [](const auto& l) { return l.motion.model != common::LandmarkMotionModel::kStatic; });
  if (movers) throw std::invalid_argument("the joint graph reference holds static landmarks only");
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    ids_.push_back(scenario.robots[i].id);
    data_[i].first_pose = common::AgentOptionsFor(scenario, ids_.back()).initial_pose;
    poses_.push_back(data_[i].first_pose);
  }
}

void JointGraphOracle::Process(const std::vector<common::SensorStep>& steps, bool solve) {
  if (steps.size() != data_.size()) throw std::invalid_argument("the joint graph reference needs one step per robot");
  const int k = static_cast<int>(data_.front().steps.size()) + 1;
  for (std::size_t j = 0; j < steps.size(); ++j) {
    robot_agent::filters::FilterEstimate identities;  // no tracks: the readings with identities only
    identities.labels_detections = true;
    identities.detection_tracks.assign(steps[j].lidar.landmarks.size(), 0);
    data_[j].steps.push_back(*robot_agent::cooperation::LabelledStep(steps[j], identities, true));
  }
  sets_.Update(k, Contacts(steps, ids_, k, scenario_.rendezvous.enable_from_step));
  if (!solve) return;
  for (int i = 0; i < sets_.robots(); ++i) poses_[static_cast<std::size_t>(i)] = Solve(i, k);
}

common::Pose2 JointGraphOracle::Solve(int i, int k) const {
  std::map<std::string, FactorLog> logs;
  for (int j = 0; j < sets_.robots(); ++j) {
    const int held = sets_.Held(i, j);
    if (held <= 0) continue;
    const FactorLog& all = data_[static_cast<std::size_t>(j)];
    FactorLog& log = logs[ids_[static_cast<std::size_t>(j)]];
    log.first_pose = all.first_pose;
    log.steps.assign(all.steps.begin(), all.steps.begin() + held);
  }
  const std::string& id = ids_[static_cast<std::size_t>(i)];
  const auto joint = robot_agent::cooperation::SolveJoint(common::AgentOptionsFor(scenario_, id), id, logs);
  if (joint.path.empty() || joint.path.back().first != k)
    throw std::logic_error("the joint graph of " + id + " does not reach step " + std::to_string(k));
  return joint.path.back().second;
}

}  // namespace mrslam::batch
