#include "scripts/batch/held_reference.h"

#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "robot_agent/cooperation/held_factors.h"
#include "robot_agent/cooperation/joint_estimate.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::batch {
namespace {

using robot_agent::cooperation::FactorLog;

// Every robot's true pose in its own frame, steps 0..run.steps.
std::vector<std::vector<common::Pose2>> TruthInOwnFrames(const common::ScenarioOptions& options) {
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const auto frames = source->Truth().frames;
  std::vector<std::vector<common::Pose2>> truth(options.robots.size());
  const auto record = [&](const common::GroundTruth& t) {
    for (std::size_t i = 0; i < truth.size(); ++i) {
      truth[i].push_back(evaluator::TruthInOwnFrame(t.robots[i].pose, frames[i].second));
    }
  };
  record(source->Truth());
  for (int k = 0; k < options.run.steps; ++k) {
    source->Step();
    record(source->Truth());
  }
  return truth;
}

double CpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

}  // namespace

int PrintHeldReference(const common::ScenarioOptions& options, const std::string& dir, bool union_all,
                       const std::string& json_path) {
  std::map<std::string, std::map<std::string, FactorLog>> held;
  std::map<std::string, FactorLog> all;
  for (const auto& robot : options.robots) {
    auto h = robot_agent::cooperation::ReadHeldFactors(robot_agent::cooperation::HeldFactorsPath(dir, robot.id));
    if (h.robot != robot.id) throw std::runtime_error("the factors of " + robot.id + " name robot " + h.robot);
    for (const auto& [origin, log] : h.logs) {
      if (log.Held() > all[origin].Held()) all[origin] = log;
    }
    held[robot.id] = std::move(h.logs);
  }
  const auto truth = TruthInOwnFrames(options);
  nlohmann::json out;
  std::printf("%-6s %10s %12s %8s %10s\n", "robot", "position_m", "heading_deg", "placed", "cpu_s");
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    const std::string& id = options.robots[i].id;
    const double start = CpuSeconds();
    const auto joint =
        robot_agent::cooperation::SolveJoint(common::AgentOptionsFor(options, id), id, union_all ? all : held.at(id));
    const double cpu = CpuSeconds() - start;
    std::vector<double> position, heading;
    for (const auto& [step, pose] : joint.path) {
      if (step < 1 || step >= static_cast<int>(truth[i].size())) continue;
      position.push_back(evaluator::PositionError(pose, truth[i][step]));
      heading.push_back(common::DegFromRad(evaluator::HeadingError(pose, truth[i][step])));
    }
    const double p = evaluator::Rmse(position), h = evaluator::Rmse(heading);
    std::printf("%-6s %10.3f %12.2f %8zu %10.2f\n", id.c_str(), p, h, joint.frames.size() + 1, cpu);
    out[id] = {
        {"position_rmse_m", p}, {"heading_rmse_deg", h}, {"robots_placed", joint.frames.size() + 1}, {"cpu_s", cpu}};
  }
  if (!json_path.empty()) std::ofstream(json_path) << out.dump(2) << "\n";
  return 0;
}

}  // namespace mrslam::batch
