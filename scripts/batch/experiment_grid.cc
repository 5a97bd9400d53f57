// mrslam_grid: paper B's experiment grid, in-process (World + one filter per robot, no DDS), or
// with --multi-process as separate processes (world_sim + one robot_agent per robot over DDS,
// one run at a time; the same seeds and the same scoring).
// For every filter, dynamism (landmark_field.moving_fraction), speed (landmark_field.speed_mps)
// and run (seed 1..N) it runs the scenario for the given frames and writes one row to
// OUT/grid.csv, then OUT/tables.md (paper B's layout: rows dynamism, columns speed; means over
// the runs) with the ratio ekf_ela / ekf and how often ekf_ela meets its targets against ekf. Metrics: paper B's,
// per robot in its own frame, then averaged over the robots (evaluator::PaperBScorer).
// Besides the filters, ekf_oracle (in-process only) is the ekf given the static landmarks'
// detections only: the grid drops the movers' detections by the simulator's truth before the
// filter sees the scan, so it scores what perfect rejection of moving landmarks reaches.
//
//   mrslam_grid --scenario FILE --out DIR [--runs N] [--frames K] [--threads T]
//               [--particles P] [--filters ekf,ekf_ela,fastslam,ekf_oracle] [--set k=v]... [--multi-process]
// A run that fails is reported and left out and the others go on; the exit code is then 3.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "common/parallel_for.h"
#include "common/progress_line.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/filters/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/node/msg_conversion.h"
#include "scripts/launch/domain_picker.h"
#include "scripts/launch/process_supervisor.h"
#include "scripts/launch/simulation_run.h"
#include "world_sim/core/world.h"
#include "world_sim/evaluator/paper_b_scorer.h"

namespace mrslam::batch {
namespace {

// The grid's axes (paper B's; --dynamism / --speeds narrow them). Set once in Main before any
// worker starts, read-only afterwards.
std::vector<double> kDynamism = {0.05, 0.20, 0.35, 0.50, 0.65, 0.80};
std::vector<double> kSpeeds = {0.1, 0.3, 0.5, 0.7, 0.9};

// One (filter, cell, run).
struct Job {
  std::string filter;
  int dynamism_index = 0;
  int speed_index = 0;
  int run = 1;
};

// Exit code when the grid ran but some of its runs failed (grid.csv and tables.md hold the others).
constexpr int kSomeRunsFailed = 3;

// Its metrics (paper B's) and its wall time.
struct Row : evaluator::PaperBScores {
  double seconds = 0.0;
  bool failed = false;  // the run threw: left out of grid.csv and of the means
};

using evaluator::MeanOfFinite;

// The ekf fed the static landmarks' detections only (see the top of this file).
constexpr const char* kOracle = "ekf_oracle";

// A job's scenario: the base with the job's filter, cell, seed and frames. The oracle's world
// labels its detections (the same draws: the labels cost none) so that the movers' can be dropped.
common::ScenarioOptions JobOptions(common::ScenarioOptions options, const Job& job, int frames) {
  options.seed = static_cast<std::uint64_t>(job.run);
  options.run.steps = frames;
  options.filter.type = job.filter == kOracle ? "ekf" : job.filter;
  if (job.filter == kOracle) options.sensors.lidar.report_identity = true;
  options.landmark_field.moving_fraction = kDynamism[job.dynamism_index];
  options.landmark_field.speed_mps = kSpeeds[job.speed_index];
  return options;
}

// The run's scorer: each robot's own frame and the lidar's range.
evaluator::PaperBScorer MakeScorer(const common::ScenarioOptions& options) {
  std::vector<common::Pose2> frames;
  for (const auto& r : options.robots) frames.push_back(r.frame_in_world);
  return evaluator::PaperBScorer(std::move(frames), options.sensors.lidar.max_range_m);
}

// What a filter's estimates report, as the scorer reads them.
std::vector<evaluator::RobotReport> Reports(const std::vector<robot_agent::filters::FilterEstimate>& estimates) {
  std::vector<evaluator::RobotReport> reports(estimates.size());
  for (std::size_t i = 0; i < estimates.size(); ++i) {
    reports[i].pose = estimates[i].pose;
    for (const auto& l : estimates[i].landmarks) {
      reports[i].landmarks.push_back({l.mean.head<2>(), l.landmark_id, l.tentative, l.moving});
    }
  }
  return reports;
}

Row Finish(const evaluator::PaperBScorer& scorer, double seconds) {
  Row row;
  static_cast<evaluator::PaperBScores&>(row) = scorer.Finish();
  row.seconds = seconds;
  return row;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The oracle's scan: the detections of the landmarks not in movers, their labels removed unless
// the scenario reports them.
void DropMovers(const std::set<int>& movers, bool keep_labels, common::LidarScan* scan) {
  std::vector<common::LandmarkDetection> kept;
  for (common::LandmarkDetection d : scan->landmarks) {
    if (movers.count(d.landmark_id) > 0) continue;
    if (!keep_labels) d.landmark_id = -1;
    kept.push_back(d);
  }
  scan->landmarks = std::move(kept);
}

// One job in-process: World + one filter per robot.
Row RunJob(const common::ScenarioOptions& base, const Job& job, int frames) {
  const auto start = std::chrono::steady_clock::now();
  const common::ScenarioOptions options = JobOptions(base, job, frames);
  world_sim::World world(options);
  const bool oracle = job.filter == kOracle;
  std::set<int> movers;  // the oracle's: the landmarks whose detections it drops
  if (oracle) {
    for (const auto& l : world.Truth().landmarks) {
      if (l.moving) movers.insert(std::stoi(l.id));
    }
  }
  std::vector<std::unique_ptr<robot_agent::filters::SlamFilter>> filters;
  for (const auto& robot : options.robots) {
    filters.push_back(robot_agent::filters::CreateFilter(common::AgentOptionsFor(options, robot.id), options.seed));
    if (!filters.back()) throw std::runtime_error("filter.type " + job.filter + " is not implemented");
  }
  evaluator::PaperBScorer scorer = MakeScorer(options);
  std::vector<robot_agent::filters::FilterEstimate> estimates(filters.size());
  for (int k = 0; k < frames; ++k) {
    std::vector<common::SensorStep> steps = world.Step();
    for (std::size_t i = 0; i < filters.size(); ++i) {
      if (oracle) DropMovers(movers, base.sensors.lidar.report_identity, &steps[i].lidar);
      filters[i]->Process(steps[i]);
      estimates[i] = filters[i]->Estimate();
    }
    scorer.AddFrame(world.Truth(), Reports(estimates));
  }
  return Finish(scorer, SecondsSince(start));
}

// What the processes of a multi-process job get besides the job's own settings.
struct MultiProcessSetup {
  std::string scenario_path;
  std::vector<std::string> overrides;  // the user's --set, then the grid's own
  std::string log_dir;
};

// What a multi-process run publishes, read over DDS: the truth and every robot's estimates, by
// step. Its readers join the domain at construction, before the run's processes start.
class RunReader {
 public:
  RunReader(int domain, const common::ScenarioOptions& options)
      : participant_({domain, "mrslam_grid", false}),
        truth_reader_(participant_, dds::kTruthTopic),
        estimates_(options.robots.size()) {
    for (const auto& robot : options.robots) {
      ids_.push_back(robot.id);
      estimate_readers_.push_back(
          std::make_unique<dds::Reader<msg::EstimatePubSubType>>(participant_, dds::EstimateTopic(robot.id)));
    }
  }

  // Takes what has arrived, waiting up to `wait` for the truth; returns whether anything had.
  bool Drain(std::chrono::milliseconds wait) {
    bool any = false;
    msg::GroundTruth t;
    while (truth_reader_.Take(&t, wait)) {
      truth_[t.stamp().step()] = dds::FromMsg(t);
      any = true;
    }
    for (std::size_t i = 0; i < estimate_readers_.size(); ++i) {
      msg::Estimate e;
      while (estimate_readers_[i]->TryTake(&e)) {
        estimates_[i][e.stamp().step()] = robot_agent::FromMsg(e);
        any = true;
      }
    }
    return any;
  }

  // Feeds steps 1..frames to the scorer; a step without its truth or an estimate throws.
  void Score(int frames, evaluator::PaperBScorer* scorer) const {
    std::vector<robot_agent::filters::FilterEstimate> frame(estimates_.size());
    for (int k = 1; k <= frames; ++k) {
      const auto step = static_cast<std::uint32_t>(k);
      if (!truth_.count(step)) throw std::runtime_error("no truth for step " + std::to_string(k));
      for (std::size_t i = 0; i < estimates_.size(); ++i) {
        const auto it = estimates_[i].find(step);
        if (it == estimates_[i].end()) {
          throw std::runtime_error("no estimate of " + ids_[i] + " for step " + std::to_string(k));
        }
        frame[i] = it->second;
      }
      scorer->AddFrame(truth_.at(step), Reports(frame));
    }
  }

 private:
  dds::Participant participant_;
  dds::Reader<msg::GroundTruthPubSubType> truth_reader_;
  std::vector<std::unique_ptr<dds::Reader<msg::EstimatePubSubType>>> estimate_readers_;
  std::vector<std::string> ids_;
  std::map<std::uint32_t, common::GroundTruth> truth_;
  std::vector<std::map<std::uint32_t, robot_agent::filters::FilterEstimate>> estimates_;
};

// The scenario overrides of a multi-process job: the setup's, then the job's filter and cell.
std::vector<std::string> JobOverrides(const MultiProcessSetup& setup, const Job& job, int frames) {
  std::vector<std::string> sets = setup.overrides;
  sets.push_back("filter.type=" + job.filter);
  sets.push_back("landmark_field.moving_fraction=" + std::to_string(kDynamism[job.dynamism_index]));
  sets.push_back("landmark_field.speed_mps=" + std::to_string(kSpeeds[job.speed_index]));
  sets.push_back("run.steps=" + std::to_string(frames));
  return sets;
}

// One job as separate processes: world_sim and one robot_agent per robot on a free DDS domain,
// in lockstep, started and supervised as the launcher does (scripts/launch/simulation_run.h);
// this process reads the truth and the estimates over DDS and scores them like an in-process run.
Row RunJobMultiProcess(const common::ScenarioOptions& base, const MultiProcessSetup& setup, const Job& job,
                       int frames) {
  const auto start = std::chrono::steady_clock::now();
  const common::ScenarioOptions options = JobOptions(base, job, frames);
  const launch::DomainReservation held = launch::PickFreeDomain(getpid());  // until the run's processes are gone
  const int domain = held.domain();
  if (domain < 0) throw std::runtime_error("no free DDS domain");
  RunReader reader(domain, options);
  const launch::RunArgs run{setup.scenario_path, domain, job.run, JobOverrides(setup, job, frames), false, ""};
  const std::string logs = setup.log_dir + "/" + job.filter + "-d" + std::to_string(job.dynamism_index) + "-s" +
                           std::to_string(job.speed_index) + "-run" + std::to_string(job.run) + "-";
  std::vector<std::string> robot_ids;
  for (const auto& robot : options.robots) robot_ids.push_back(robot.id);
  launch::ProcessSupervisor children;
  launch::StartSimulation(&children, run, robot_ids, 1, 1, logs);
  const std::atomic<bool> never{false};
  const launch::RunEnd end = launch::SuperviseRun(&children, {start, 60.0 + frames}, never,
                                                  [&] { reader.Drain(std::chrono::milliseconds(20)); });
  if (end.kind != launch::RunEnd::Kind::kDone) {
    children.StopAll(std::chrono::seconds(2));
    if (end.failure) {
      throw std::runtime_error(end.failure->name + " " + end.failure->Describe() + "; log: " + end.failure->log_path);
    }
    throw std::runtime_error("a multi-process run did not finish within " + std::to_string(60 + frames) +
                             " s; logs: " + logs + "*.log");
  }
  while (reader.Drain(std::chrono::milliseconds(300))) {
  }
  evaluator::PaperBScorer scorer = MakeScorer(options);
  reader.Score(frames, &scorer);
  return Finish(scorer, SecondsSince(start));
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// tables.md: paper B's layout (rows dynamism, columns speed), each cell the mean over the runs of
// that cell that finished, and how ekf_ela does against ekf when both ran.
class GridTables {
 public:
  GridTables(const std::vector<Job>& jobs, const std::vector<Row>& rows, std::vector<std::string> filters)
      : filters_(std::move(filters)), jobs_(jobs.size()) {
    for (std::size_t j = 0; j < jobs.size(); ++j) {
      num_robots_ = std::max(num_robots_, rows[j].robot_rmse_per_robot_m.size());
      if (rows[j].failed) {
        ++failed_;
        continue;
      }
      cells_[{jobs[j].filter, jobs[j].dynamism_index, jobs[j].speed_index}].push_back(&rows[j]);
    }
    for (std::size_t f = 0; f < filters_.size(); ++f) filter_names_ += (f ? " / " : "") + filters_[f];
  }

  void Write(const std::string& path, int runs, int frames, int particles, double seconds, bool multi_process) const {
    std::ofstream out(path);
    if (!out) throw std::runtime_error("cannot write " + path);
    out << "# Paper B's grid (" << (multi_process ? "multi-process" : "in-process") << ")\n\n";
    out << "Means over " << runs << " runs (seeds 1.." << runs << ") of " << frames
        << " frames, 3 robots; rows: dynamism (share of moving landmarks), columns: landmark speed (m/s). "
        << "fastslam with constant_turn_rate tracking and " << particles << " particles. ";
    out << fmt::format("Wall time of the grid: {:.0f} s.", seconds);
    if (failed_ > 0) out << " " << failed_ << " of " << jobs_ << " runs failed and are left out of the means.";
    out << "\n\n";
    WriteMetricTables(out);
    const bool have_pair =
        std::count(filters_.begin(), filters_.end(), "ekf") && std::count(filters_.begin(), filters_.end(), "ekf_ela");
    if (have_pair) WriteTargets(out);
  }

 private:
  using CellKey = std::tuple<std::string, int, int>;
  struct Metric {
    const char* title;
    double Row::*field;
  };

  // The runs of (filter, cell) that finished.
  const std::vector<const Row*>& Cell(const std::string& f, int d, int s) const {
    static const std::vector<const Row*> kNone;
    const auto it = cells_.find({f, d, s});
    return it == cells_.end() ? kNone : it->second;
  }
  double MeanOf(const std::string& f, int d, int s, double Row::*field) const {
    std::vector<double> v;
    for (const Row* r : Cell(f, d, s)) v.push_back(r->*field);
    return MeanOfFinite(v);
  }
  // One markdown table: rows dynamism, columns speed, cell(d, s) as text.
  static void Table(std::ostream& out, const std::string& heading, const std::function<std::string(int, int)>& cell) {
    out << "## " << heading << "\n\n| dynamism |";
    for (const double sp : kSpeeds) out << fmt::format(" {:.1f} m/s |", sp);
    out << "\n|---|";
    for (std::size_t sp = 0; sp < kSpeeds.size(); ++sp) out << "---|";
    out << "\n";
    for (std::size_t d = 0; d < kDynamism.size(); ++d) {
      out << fmt::format("| {:.0f} % |", 100.0 * kDynamism[d]);
      for (std::size_t sp = 0; sp < kSpeeds.size(); ++sp) {
        out << " " << cell(static_cast<int>(d), static_cast<int>(sp)) << " |";
      }
      out << "\n";
    }
    out << "\n";
  }
  // "a / b / c" over the filters.
  std::string PerFilter(const std::function<double(const std::string&)>& value) const {
    std::string text;
    for (std::size_t f = 0; f < filters_.size(); ++f)
      text += fmt::format("{}{:.2f}", f ? " / " : "", value(filters_[f]));
    return text;
  }

  // The metrics' tables over the filters, then paper B's per-robot position RMSE (its tables 2-4).
  void WriteMetricTables(std::ostream& out) const {
    const Metric metrics[] = {{"Total landmark RMSE (m), eqs. 17-18", &Row::landmark_rmse_m},
                              {"Robot position RMSE (m), mean over robots", &Row::robot_rmse_m},
                              {"Static-landmark completeness at the end", &Row::static_completeness},
                              {"Static-landmark completeness at the end, map points assigned among the static "
                               "landmarks only",
                               &Row::static_only_completeness}};
    for (const auto& m : metrics) {
      Table(out, std::string(m.title) + ": " + filter_names_,
            [&](int d, int sp) { return PerFilter([&](const std::string& f) { return MeanOf(f, d, sp, m.field); }); });
    }
    for (std::size_t robot = 0; robot < num_robots_; ++robot) {
      Table(out, "Position RMSE (m) of robot " + std::to_string(robot + 1) + ": " + filter_names_, [&](int d, int sp) {
        return PerFilter([&](const std::string& f) {
          std::vector<double> v;
          for (const Row* r : Cell(f, d, sp)) v.push_back(r->robot_rmse_per_robot_m[robot]);
          return MeanOfFinite(v);
        });
      });
    }
  }

  // The ratios ekf_ela / ekf and how many cells meet each target.
  void WriteTargets(std::ostream& out) const {
    const Metric ratios[] = {{"Ratio ekf_ela / ekf, landmark RMSE", &Row::landmark_rmse_m},
                             {"Ratio ekf_ela / ekf, robot RMSE", &Row::robot_rmse_m}};
    for (const auto& m : ratios) {
      Table(out, m.title, [&](int d, int sp) {
        return fmt::format("{:.2f}", MeanOf("ekf_ela", d, sp, m.field) / MeanOf("ekf", d, sp, m.field));
      });
    }
    int lm_better = 0, robot_better = 0, ratio_ok = 0, ratio_cells = 0, completeness_ok = 0;
    for (std::size_t d = 0; d < kDynamism.size(); ++d) {
      for (std::size_t s = 0; s < kSpeeds.size(); ++s) {
        const int di = static_cast<int>(d), si = static_cast<int>(s);
        const double lm =
            MeanOf("ekf_ela", di, si, &Row::landmark_rmse_m) / MeanOf("ekf", di, si, &Row::landmark_rmse_m);
        if (lm < 1.0) ++lm_better;
        if (MeanOf("ekf_ela", di, si, &Row::robot_rmse_m) < MeanOf("ekf", di, si, &Row::robot_rmse_m)) ++robot_better;
        if (kDynamism[d] >= 0.35 - 1e-9) {
          ++ratio_cells;
          if (lm <= 0.6) ++ratio_ok;
        }
        if (MeanOf("ekf_ela", di, si, &Row::static_completeness) >=
            MeanOf("ekf", di, si, &Row::static_completeness) - 0.05) {
          ++completeness_ok;
        }
      }
    }
    const int total = static_cast<int>(kDynamism.size() * kSpeeds.size());
    const int at_least = total - total / 10;  // 27 of 30
    out << "## ekf_ela against ekf (targets), on the means above\n\n";
    out << "- ekf_ela better than ekf on landmark RMSE: " << lm_better << "/" << total << " cells (target " << total
        << ")\n";
    out << "- ekf_ela better than ekf on robot RMSE: " << robot_better << "/" << total
        << " cells (target >= " << at_least << ")\n";
    out << "- ekf_ela landmark RMSE <= 0.6 of ekf's at dynamism >= 35 %: " << ratio_ok << "/" << ratio_cells
        << " cells\n";
    out << "- ekf_ela static completeness at most 0.05 below ekf's: " << completeness_ok << "/" << total << " cells\n";
  }

  std::vector<std::string> filters_;
  std::string filter_names_;
  std::size_t jobs_ = 0, failed_ = 0, num_robots_ = 0;
  std::map<CellKey, std::vector<const Row*>> cells_;
};

// The filters of --filters; throws for an unknown one, or the oracle with --multi-process.
std::vector<std::string> ParseFilters(const std::string& text, bool multi_process) {
  std::vector<std::string> filters = Split(text);
  for (const auto& f : filters) {
    if (f != "ekf" && f != "ekf_ela" && f != "fastslam" && f != kOracle) {
      throw std::runtime_error("unknown filter '" + f + "' (ekf, ekf_ela, fastslam or " + kOracle + ")");
    }
    if (f == kOracle && multi_process) {
      throw std::runtime_error(std::string(kOracle) + " runs in-process only (the agents see no truth)");
    }
  }
  return filters;
}

// Jobs cell by cell, so that progress counts finished cells.
std::vector<Job> MakeJobs(const std::vector<std::string>& filters, int runs) {
  std::vector<Job> jobs;
  for (int d = 0; d < static_cast<int>(kDynamism.size()); ++d) {
    for (int s = 0; s < static_cast<int>(kSpeeds.size()); ++s) {
      for (int r = 1; r <= runs; ++r) {
        for (const auto& f : filters) jobs.push_back({f, d, s, r});
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
                   const std::vector<Job>& jobs, int frames, int threads, int jobs_per_cell) {
  const int num_jobs = static_cast<int>(jobs.size());
  const int num_cells = static_cast<int>(kDynamism.size() * kSpeeds.size());
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
                   jobs[j].filter.c_str(), kDynamism[jobs[j].dynamism_index], kSpeeds[jobs[j].speed_index],
                   errors[j].c_str());
      if (result.failed++ == 0) result.first_error = errors[j];
    }
    const int cell = jobs[j].dynamism_index * static_cast<int>(kSpeeds.size()) + jobs[j].speed_index;
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
    csv << jobs[j].filter << "," << num(kDynamism[jobs[j].dynamism_index]) << "," << num(kSpeeds[jobs[j].speed_index])
        << "," << jobs[j].run << "," << num(r.landmark_rmse_m) << "," << num(r.robot_rmse_m) << ","
        << num(r.static_completeness) << "," << num(r.static_only_completeness);
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
  app.add_option("--dynamism", kDynamism, "Shares of moving landmarks (default paper B's)");
  app.add_option("--speeds", kSpeeds, "Landmark speeds, m/s (default paper B's)");
  app.add_option("--set", overrides, "Override a scenario key: key.path=value (repeatable)");
  bool multi_process = false;
  app.add_flag("--multi-process", multi_process,
               "Run every job as separate processes (world_sim + robot_agent per robot, over DDS), one at a time");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
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

  const std::vector<Job> jobs = MakeJobs(filters, runs);
  const int num_jobs = static_cast<int>(jobs.size());
  const GridResult grid = RunJobs(options, multi_process ? &setup : nullptr, jobs, frames, threads,
                                  runs * static_cast<int>(filters.size()));
  WriteCsv(out_dir + "/grid.csv", options, jobs, grid.rows);
  GridTables(jobs, grid.rows, filters)
      .Write(out_dir + "/tables.md", runs, frames, particles, grid.seconds, multi_process);
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
