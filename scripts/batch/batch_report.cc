#include "scripts/batch/batch_report.h"

#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "common/parallel_for.h"
#include "common/progress_line.h"

namespace mrslam::batch {

double Metric(const RobotRun& r, int i) {
  // In the order of kMetricNames.
  static constexpr double RobotRun::*kMembers[] = {&RobotRun::position_rmse_m,        &RobotRun::heading_rmse_deg,
                                                   &RobotRun::landmark_rmse_m,        &RobotRun::dead_reckoning_rmse_m,
                                                   &RobotRun::static_landmark_rmse_m, &RobotRun::moving_landmark_rmse_m,
                                                   &RobotRun::moving_completeness,    &RobotRun::mean_nees,
                                                   &RobotRun::own_landmark_rmse_m};
  static_assert(std::size(kMembers) == std::size(kMetricNames));
  return r.*kMembers[i];
}

void ForEachSeed(int num_tasks, int threads, const std::function<void(int)>& fn) {
  common::ProgressLine progress;
  try {
    common::ParallelFor(num_tasks, threads, fn, [&](int /*task*/, int done) {
      progress.Show("seeds done: " + std::to_string(done) + "/" + std::to_string(num_tasks), done == num_tasks);
    });
  } catch (const std::exception&) {
    progress.Finish();
    throw;
  }
  progress.Finish();
}

nlohmann::json StartReport(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds,
                           const std::string& what) {
  const std::uint64_t last_seed = first_seed + num_seeds - 1;
  std::printf("scenario %s, seeds %llu..%llu, %s\n", options.name.c_str(),
              static_cast<unsigned long long>(first_seed),  // NOLINT(runtime/int)
              static_cast<unsigned long long>(last_seed),   // NOLINT(runtime/int)
              what.c_str());
  nlohmann::json json;
  json["scenario"] = options.name;
  json["seeds"] = {first_seed, last_seed};
  return json;
}

void WriteJson(const nlohmann::json& json, const std::string& path) {
  if (path.empty()) return;
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << json.dump(2) << "\n";
}

}  // namespace mrslam::batch
