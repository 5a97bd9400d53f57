#pragma once

#include <cstdint>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "common/config/scenario_options.h"
#include "common/sensor_types.h"
#include "world_sim/evaluator/robot_estimate.h"

// A run as the viewer shows it (mrslam_view, docs/viewer.md): a header (the scenario's robots
// and their frames) and one JSON object per step (the truth in W, every robot's estimate and
// map in its own frame G_i, live also its lidar). The evaluator writes them as view.jsonl; the
// viewer builds the same objects from DDS while a run goes. Pure: no DDS.
namespace mrslam::evaluator {

// {"scenario", "seed", "steps", "dt_s", "robots": [{"id", "frame": [x, y, heading]}]}: the pose
// of every robot's frame G_i in W.
nlohmann::json ViewHeader(const common::ScenarioOptions& scenario);

// What the view shows of one step. Any part may be missing (null truth; robots without an
// estimate or a scan yet).
struct ViewStepInput {
  std::uint32_t step = 0;
  double time_s = 0.0;
  const common::GroundTruth* truth = nullptr;
  std::map<std::string, const RobotEstimate*> estimates;
  std::map<std::string, const common::LidarScan*> scans;
};

// {"step", "time_s", "truth": {"step", "robots": {id: [x, y, heading]}, "landmarks": [[id, x,
// y, moving]]}, "estimates": {id: {"step", "pose", "cov": [xx, xy, yy, hh], "landmarks": [[x, y,
// cxx, cxy, cyy, moving, heading, v, id]], "frames_known", "rendezvous": [[peer, step]],
// "rejected"}}, "lidar": {id: [[range, bearing]]}}. Numbers keep 6 significant digits.
nlohmann::json ViewStep(const ViewStepInput& input);

}  // namespace mrslam::evaluator
