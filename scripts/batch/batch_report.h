#pragma once

#include <cstdint>
#include <functional>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

#include "common/config/scenario_options.h"

// What mrslam_batch's modes share: one robot's figures of a run, the seeds' worker pool, and
// the report's first line and JSON file.
namespace mrslam::batch {

// The metrics of one robot in one run.
struct RobotRun {
  double position_rmse_m = 0.0;
  double heading_rmse_deg = 0.0;
  double landmark_rmse_m = 0.0;
  double dead_reckoning_rmse_m = 0.0;
  double static_landmark_rmse_m = 0.0;
  double moving_landmark_rmse_m = 0.0;
  double moving_completeness = 0.0;
  double mean_nees = 0.0;
  double own_landmark_rmse_m = 0.0;
};

// The names of summary.json (docs/metrics.md).
inline constexpr const char* kMetricNames[] = {
    "position_rmse_m",        "heading_rmse_deg",       "landmark_rmse_m",     "dead_reckoning_rmse_m",
    "static_landmark_rmse_m", "moving_landmark_rmse_m", "moving_completeness", "mean_nees",
    "own_landmark_rmse_m"};
inline constexpr int kNumMetrics = static_cast<int>(std::size(kMetricNames));
// The figure kMetricNames[i] of r.
double Metric(const RobotRun& r, int i);

// Runs fn(task) for task in [0, num_tasks) on `threads` worker threads (common::ParallelFor),
// with progress on stderr; the first error stops the others and is rethrown.
void ForEachSeed(int num_tasks, int threads, const std::function<void(int)>& fn);

// Prints the first line of a report ("scenario NAME, seeds A..B, WHAT") and returns the report's
// JSON with the scenario and the seeds.
nlohmann::json StartReport(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds,
                           const std::string& what);

// Writes the report's JSON to path; nothing for an empty path.
void WriteJson(const nlohmann::json& json, const std::string& path);

}  // namespace mrslam::batch
