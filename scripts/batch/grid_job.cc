#include "scripts/batch/grid_job.h"

#include <cstdint>

namespace mrslam::batch {

common::ScenarioOptions JobOptions(common::ScenarioOptions options, const Job& job, int frames) {
  options.seed = static_cast<std::uint64_t>(job.run);
  options.run.steps = frames;
  options.filter.type = job.filter == kOracle ? "ekf" : job.filter;
  if (job.filter == kOracle) options.sensors.lidar.report_identity = true;
  options.landmark_field.moving_fraction = job.dynamism;
  options.landmark_field.speed_mps = job.speed_mps;
  return options;
}

std::vector<std::string> JobOverrides(const MultiProcessSetup& setup, const Job& job, int frames) {
  std::vector<std::string> sets = setup.overrides;
  sets.push_back("filter.type=" + job.filter);
  sets.push_back("landmark_field.moving_fraction=" + std::to_string(job.dynamism));
  sets.push_back("landmark_field.speed_mps=" + std::to_string(job.speed_mps));
  sets.push_back("run.steps=" + std::to_string(frames));
  return sets;
}

}  // namespace mrslam::batch
