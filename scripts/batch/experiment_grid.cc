// mrslam_grid: paper B's experiment grid, in-process (World + one filter per robot, no DDS), or
// with --multi-process as separate processes (world_sim + one robot_agent per robot over DDS,
// one run at a time; the same seeds and the same scoring).
// For every filter, dynamism (landmark_field.moving_fraction), speed (landmark_field.speed_mps)
// and run (seed 1..N) it runs the scenario for the given frames and writes one row to
// OUT/grid.csv, then OUT/tables.md (paper B's layout: rows dynamism, columns speed; means over
// the runs) with the ratio ekf_ela / ekf and how often ekf_ela meets its targets against ekf.
// Metrics: paper B's, per robot in its own frame, then averaged over the robots
// (evaluator::PaperBScorer).
// Besides the filters, ekf_oracle (in-process only) is the ekf given the static landmarks'
// detections only: the grid drops the movers' detections by the simulator's truth before the
// filter sees the scan, so it scores what perfect rejection of moving landmarks reaches.
//
//   mrslam_grid --scenario FILE --out DIR [--runs N] [--frames K] [--threads T]
//               [--particles P] [--filters ekf,ekf_ela,fastslam,smoother,ekf_oracle] [--set k=v]... [--multi-process]
// A run that fails is reported and left out and the others go on; the exit code is then 3.
// The jobs are grid_job's, a run and its scoring grid_run's, tables.md grid_tables'.
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "common/app.h"
#include "common/config/scenario_options.h"
#include "common/parallel_for.h"
#include "common/progress_line.h"
#include "scripts/batch/grid_job.h"
#include "scripts/batch/grid_run.h"
#include "scripts/batch/grid_tables.h"

namespace mrslam::batch {
namespace {

// Exit code when the grid ran but some of its runs failed (grid.csv and tables.md hold the others).
constexpr int kSomeRunsFailed = 3;

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// The filters of --filters; throws for an unknown one, or the oracle with --multi-process.
std::vector<std::string> ParseFilters(const std::string& text, bool multi_process) {
  std::vector<std::string> filters = Split(text);
  for (const auto& f : filters) {
    if (f != "ekf" && f != "ekf_ela" && f != "fastslam" && f != "smoother" && f != kOracle) {
      throw std::runtime_error("unknown filter '" + f + "' (ekf, ekf_ela, fastslam, smoother or " + kOracle + ")");
    }
    if (f == kOracle && multi_process) {
      throw std::runtime_error(std::string(kOracle) + " runs in-process only (the agents see no truth)");
    }
  }
  return filters;
}

// Jobs cell by cell, so that progress counts finished cells.
std::vector<Job> MakeJobs(const std::vector<std::string>& filters, int runs, const GridAxes& axes) {
  std::vector<Job> jobs;
  for (int d = 0; d < static_cast<int>(axes.dynamism.size()); ++d) {
    for (int s = 0; s < static_cast<int>(axes.speeds.size()); ++s) {
      for (int r = 1; r <= runs; ++r) {
        for (const auto& f : filters) jobs.push_back({f, d, s, r, axes.dynamism[d], axes.speeds[s]});
      }
    }
  }
  return jobs;
}

// Every job's row, how many failed (and the first error), and the grid's wall time.
struct GridResult {
  std::vector<Row> rows;
  int failed = 0;
  std::string first_error;
  double seconds = 0.0;
};

// Runs the jobs on `threads` workers (one with --multi-process: each run's processes use every
// core), with progress by finished cells. A run that fails is counted and left out; the others go
// on.
GridResult RunJobs(const common::ScenarioOptions& options, const MultiProcessSetup* multi_process,
                   const std::vector<Job>& jobs, int frames, int threads, int jobs_per_cell, std::size_t num_speeds) {
  const int num_jobs = static_cast<int>(jobs.size());
  const int num_cells = static_cast<int>(jobs.size()) / jobs_per_cell;
  GridResult result;
  result.rows.resize(jobs.size());
  std::vector<std::string> errors(jobs.size());
  std::vector<int> cell_left(num_cells, jobs_per_cell);
  int cells_done = 0;
  common::ProgressLine progress;
  const auto start = std::chrono::steady_clock::now();
  const auto run = [&](int j) {
    try {
      result.rows[j] = multi_process != nullptr ? RunJobMultiProcess(options, *multi_process, jobs[j], frames)
                                                : RunJob(options, jobs[j], frames);
    } catch (const std::exception& e) {
      errors[j] = e.what();
      result.rows[j].failed = true;
    }
  };
  const auto done = [&](int j, int finished) {
    if (result.rows[j].failed) {
      progress.Finish();
      std::fprintf(stderr, "mrslam_grid: run %d of %s at dynamism %g, speed %g m/s failed: %s\n", jobs[j].run,
                   jobs[j].filter.c_str(), jobs[j].dynamism, jobs[j].speed_mps, errors[j].c_str());
      if (result.failed++ == 0) result.first_error = errors[j];
    }
    const int cell = jobs[j].dynamism_index * static_cast<int>(num_speeds) + jobs[j].speed_index;
    if (--cell_left[cell] == 0) ++cells_done;
    const double elapsed = SecondsSince(start);
    const double left = elapsed / finished * (num_jobs - finished);
    progress.Show(fmt::format("cells {}/{}, runs {}/{}, elapsed {:.0f} s, left ~{:.0f} s", cells_done, num_cells,
                              finished, num_jobs, elapsed, left),
                  finished == num_jobs);
  };
  common::ParallelFor(num_jobs, multi_process != nullptr ? 1 : threads, run, done);
  progress.Finish();
  result.seconds = SecondsSince(start);
  return result;
}

// grid.csv: one row per job that finished.
void WriteCsv(const std::string& path, const common::ScenarioOptions& options, const std::vector<Job>& jobs,
              const std::vector<Row>& rows) {
  std::ofstream csv(path);
  if (!csv) throw std::runtime_error("cannot write " + path);
  csv << "filter,dynamism,speed_mps,run,landmark_rmse_m,robot_rmse_m,static_completeness,static_only_completeness";
  for (const auto& r : options.robots) csv << "," << r.id << "_landmark_rmse_m";
  for (const auto& r : options.robots) csv << "," << r.id << "_robot_rmse_m";
  for (const auto& r : options.robots) csv << "," << r.id << "_static_completeness";
  csv << ",moving_flag_share,mapped_at_end,seconds\n";
  char buf[64];
  auto num = [&](double v) {
    std::snprintf(buf, sizeof(buf), "%.6g", v);
    return std::string(buf);
  };
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    const Row& r = rows[j];
    if (r.failed) continue;
    csv << jobs[j].filter << "," << num(jobs[j].dynamism) << "," << num(jobs[j].speed_mps) << "," << jobs[j].run << ","
        << num(r.landmark_rmse_m) << "," << num(r.robot_rmse_m) << "," << num(r.static_completeness) << ","
        << num(r.static_only_completeness);
    for (const double v : r.robot_landmark_rmse_m) csv << "," << num(v);
    for (const double v : r.robot_rmse_per_robot_m) csv << "," << num(v);
    for (const double v : r.robot_completeness) csv << "," << num(v);
    csv << "," << num(r.moving_flag_share) << "," << num(r.mapped_at_end) << "," << num(r.seconds) << "\n";
  }
}

int Main(int argc, char** argv) {
  CLI::App app{"Paper B's experiment grid, in-process (World + one filter per robot, no DDS) or multi-process."};
  std::string scenario_path, out_dir, filters_text = "ekf,ekf_ela,fastslam";
  std::vector<std::string> overrides;
  int runs = 10, frames = 150, threads = 2, particles = 100;
  app.add_option("--scenario", scenario_path, "Scenario YAML file (paper B's world)")->required();
  app.add_option("--out", out_dir, "Output folder (grid.csv, tables.md)")->required();
  app.add_option("--runs", runs, "Runs per cell (seeds 1..N)")->check(CLI::Range(1, 1000));
  app.add_option("--frames", frames, "Frames per run")->check(CLI::Range(1, 100000));
  app.add_option("--threads", threads, "Worker threads")->check(CLI::Range(1, 256));
  app.add_option("--particles", particles, "FastSLAM particles")->check(CLI::Range(1, 100000));
  app.add_option("--filters", filters_text, "Comma-separated filters");
  GridAxes axes;
  app.add_option("--dynamism", axes.dynamism, "Shares of moving landmarks (default paper B's)");
  app.add_option("--speeds", axes.speeds, "Landmark speeds, m/s (default paper B's)");
  app.add_option("--set", overrides, "Override a scenario key: key.path=value (repeatable)");
  bool multi_process = false;
  app.add_flag("--multi-process", multi_process,
               "Run every job as separate processes (world_sim + robot_agent per robot, over DDS), one at a time");
  if (const auto status = common::ParseCommandLine("mrslam_grid", app, argc, argv)) return *status;
  common::ScenarioOptions options = common::LoadScenario(scenario_path, overrides);
  if (!options.landmark_field.enabled) throw std::runtime_error(scenario_path + " has no landmark_field");
  options.filter.particles = particles;
  options.filter.landmark_kinematics = robot_agent::LandmarkKinematics::kConstantTurnRate;
  const std::vector<std::string> filters = ParseFilters(filters_text, multi_process);
  std::filesystem::create_directories(out_dir);
  MultiProcessSetup setup{scenario_path, overrides, out_dir + "/logs"};
  setup.overrides.push_back("filter.particles=" + std::to_string(particles));
  setup.overrides.push_back("filter.landmark_kinematics=constant_turn_rate");
  if (multi_process) std::filesystem::create_directories(setup.log_dir);

  const std::vector<Job> jobs = MakeJobs(filters, runs, axes);
  const int num_jobs = static_cast<int>(jobs.size());
  const GridResult grid = RunJobs(options, multi_process ? &setup : nullptr, jobs, frames, threads,
                                  runs * static_cast<int>(filters.size()), axes.speeds.size());
  WriteCsv(out_dir + "/grid.csv", options, jobs, grid.rows);
  WriteGridTables(out_dir + "/tables.md", jobs, grid.rows, filters, axes, runs, frames, particles, grid.seconds,
                  multi_process);
  std::printf("grid: %d runs in %.0f s; wrote %s/grid.csv and %s/tables.md\n", num_jobs, grid.seconds, out_dir.c_str(),
              out_dir.c_str());
  std::fflush(stdout);
  if (grid.failed > 0) {
    std::fprintf(stderr, "mrslam_grid: error: %d of %d runs failed, left out of grid.csv and tables.md (first: %s)\n",
                 grid.failed, num_jobs, grid.first_error.c_str());
    return kSomeRunsFailed;
  }
  return 0;
}

}  // namespace
}  // namespace mrslam::batch

int main(int argc, char** argv) {
  try {
    return mrslam::batch::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mrslam_grid: error: %s\n", e.what());
    return 1;
  }
}
