#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"
#include "world_sim/evaluator/paper_b_scorer.h"

// mrslam_grid's jobs: paper B's axes, one run of one filter in one cell, its scenario and its
// figures.
namespace mrslam::batch {

// The grid's axes (paper B's by default; --dynamism and --speeds narrow them).
struct GridAxes {
  std::vector<double> dynamism = {0.05, 0.20, 0.35, 0.50, 0.65, 0.80};  // landmark_field.moving_fraction
  std::vector<double> speeds = {0.1, 0.3, 0.5, 0.7, 0.9};               // landmark_field.speed_mps
};

// One (filter, cell, run): the cell's indices into the axes and their values.
struct Job {
  std::string filter;
  int dynamism_index = 0;
  int speed_index = 0;
  int run = 1;
  double dynamism = 0.0;
  double speed_mps = 0.0;
};

// Its metrics (paper B's) and its wall time.
struct Row : evaluator::PaperBScores {
  double seconds = 0.0;
  bool failed = false;  // the run threw: left out of grid.csv and of the means
};

// The ekf fed the static landmarks' detections only (see experiment_grid.cc).
inline constexpr const char* kOracle = "ekf_oracle";

// A job's scenario: the base with the job's filter, cell, seed and frames. The oracle's world
// labels its detections (the same draws: the labels cost none) so that the movers' can be dropped.
common::ScenarioOptions JobOptions(common::ScenarioOptions options, const Job& job, int frames);

// What the processes of a multi-process job get besides the job's own settings.
struct MultiProcessSetup {
  std::string scenario_path;
  std::vector<std::string> overrides;  // the user's --set, then the grid's own
  std::string log_dir;
};

// The scenario overrides of a multi-process job: the setup's, then the job's filter and cell.
std::vector<std::string> JobOverrides(const MultiProcessSetup& setup, const Job& job, int frames);

inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace mrslam::batch
