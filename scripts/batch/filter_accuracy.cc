#include "scripts/batch/filter_accuracy.h"

#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "common/config/agent_options_projection.h"
#include "common/progress_line.h"
#include "common/se2.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "scripts/batch/batch_report.h"
#include "scripts/batch/joint_graph_oracle.h"
#include "scripts/batch/joint_oracle.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/evaluator/robot_scorer.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::batch {
namespace {

// A robot's current pose and map (landmark positions with their identities).
struct Output {
  common::Pose2 pose;
  std::optional<Eigen::Matrix3d> covariance;  // none from a reference
  std::vector<evaluator::MapPoint> map;
};

// A reference's output: its first robot's pose and every landmark it holds.
Output OutputOf(const robot_agent::smoother::BatchSmoother& reference) {
  Output out;
  out.pose = reference.Pose();
  for (const auto& [position, id] : reference.Landmarks()) out.map.push_back({position, id});
  return out;
}

// One robot's estimator in a run: its own filter, or its reference (alone).
class Estimator {
 public:
  Estimator(const common::ScenarioOptions& options, int robot_index, std::uint64_t seed, bool reference) {
    if (reference) {
      reference_ = MakeOracleReference(options, FieldStatics(options), {robot_index}, {}, 0);
    } else {
      filter_ =
          robot_agent::factory::CreateFilter(common::AgentOptionsFor(options, options.robots[robot_index].id), seed);
      if (!filter_) throw std::runtime_error("filter.type " + options.filter.type + " is not implemented");
    }
  }
  // A reference solves only when asked (the step's data added regardless); a filter takes every step.
  void Process(const common::SensorStep& step, bool solve) {
    if (filter_) {
      filter_->Process(step);
    } else {
      reference_->Add({step});
      if (solve) reference_->Solve();
    }
  }
  Output Estimate() const {
    if (!filter_) return OutputOf(*reference_);
    Output out;
    const robot_agent::filters::FilterEstimate e = filter_->Estimate();
    out.pose = e.pose;
    out.covariance = e.covariance;
    for (const auto& l : e.landmarks) out.map.push_back({l.mean.head<2>(), l.landmark_id});
    return out;
  }

 private:
  std::unique_ptr<robot_agent::filters::SlamFilter> filter_;
  std::unique_ptr<robot_agent::smoother::BatchSmoother> reference_;
};

// Every robot's estimator in a run: one Estimator each, or the causal joint oracle of the team.
class Team {
 public:
  Team(const common::ScenarioOptions& options, std::uint64_t seed, Estimators estimators,
       const std::vector<std::pair<std::string, common::Pose2>>& frames) {
    if (estimators == Estimators::kJointReference) {
      joint_ = std::make_unique<JointOracle>(options, frames);
      return;
    }
    if (estimators == Estimators::kJointGraphReference) {
      graph_ = std::make_unique<JointGraphOracle>(options);
      return;
    }
    for (std::size_t i = 0; i < options.robots.size(); ++i) {
      own_.emplace_back(options, static_cast<int>(i), seed, estimators == Estimators::kReference);
    }
  }
  void Process(const std::vector<common::SensorStep>& steps, bool solve) {
    if (joint_) joint_->Process(steps, solve);
    if (graph_) graph_->Process(steps, solve);
    for (std::size_t i = 0; i < own_.size(); ++i) own_[i].Process(steps[i], solve);
  }
  Output Estimate(std::size_t i) const {
    if (graph_) return {graph_->Pose(static_cast<int>(i)), std::nullopt, {}};
    return joint_ ? OutputOf(joint_->Of(static_cast<int>(i))) : own_[i].Estimate();
  }

 private:
  std::vector<Estimator> own_;
  std::unique_ptr<JointOracle> joint_;
  std::unique_ptr<JointGraphOracle> graph_;
};

// One seed's metrics per robot (scenario order).
std::vector<RobotRun> RunSeed(const common::ScenarioOptions& options, std::uint64_t seed, Estimators estimators,
                              bool progress, int every) {
  common::ProgressLine line;
  const std::size_t last = options.robots.size() - 1;
  const StepObserver observer = [&](std::size_t robot, const common::SensorStep& step, const evaluator::StepScore&) {
    if (robot != last) return;
    const int k = static_cast<int>(step.lidar.stamp.step);
    line.Show("seed " + std::to_string(seed) + ": step " + std::to_string(k) + "/" + std::to_string(options.run.steps),
              k == options.run.steps);
  };
  std::vector<RobotRun> out;
  for (const evaluator::RobotSummary& s :
       ScoreSeed(options, seed, estimators, progress ? observer : StepObserver{}, every)) {
    out.push_back({s.position_rmse_m, s.heading_rmse_deg, s.landmark_rmse_m, s.dead_reckoning_rmse_m,
                   s.static_landmark_rmse_m, s.moving_landmark_rmse_m, s.moving_completeness, s.mean_nees,
                   s.own_landmark_rmse_m});
  }
  return out;
}

// The report's name of the estimators.
std::string Describe(const common::ScenarioOptions& options, Estimators estimators) {
  switch (estimators) {
    case Estimators::kReference:
      return "the MAP reference";
    case Estimators::kJointReference:
      return "the causal joint MAP reference";
    case Estimators::kJointGraphReference:
      return "the causal joint graph reference (poses only)";
    default:
      return options.filter.type + " with " + std::to_string(options.filter.particles) + " particles";
  }
}

}  // namespace

std::vector<evaluator::RobotSummary> ScoreSeed(common::ScenarioOptions options, std::uint64_t seed,
                                               Estimators estimators, const StepObserver& observer, int every) {
  if (every < 1) throw std::invalid_argument("every must be at least 1");
  options.seed = seed;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const common::GroundTruth truth0 = source->Truth();
  const std::size_t n = options.robots.size();
  Team team(options, seed, estimators, truth0.frames);
  std::vector<evaluator::RobotScorer> scorers;
  for (std::size_t i = 0; i < n; ++i) {
    const common::Pose2& frame = truth0.frames[i].second;
    scorers.emplace_back(frame, evaluator::TruthInOwnFrame(truth0.robots[i].pose, frame), options.sensors.lidar);
  }
  std::vector<common::Odometry> odometry(n);  // since the last step scored
  for (int k = 1; k <= options.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    const common::GroundTruth truth = source->Truth();
    const bool scored = k % every == 0 || k == options.run.steps;
    team.Process(steps, scored);
    for (std::size_t i = 0; i < n; ++i) {
      auto& segments = odometry[i].segments;
      segments.insert(segments.end(), steps[i].odometry.segments.begin(), steps[i].odometry.segments.end());
      if (!scored) continue;
      const Output e = team.Estimate(i);
      const evaluator::StepScore score =
          scorers[i].Add(truth, truth.robots[i].pose, e.pose, e.covariance, e.map, &odometry[i]);
      segments.clear();
      if (observer) observer(i, steps[i], score);
    }
  }
  std::vector<evaluator::RobotSummary> out;
  out.reserve(n);
  for (const auto& scorer : scorers) out.push_back(scorer.Summary());
  return out;
}

int PrintFilterAccuracy(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                        const std::string& json_path, Estimators estimators, int every) {
  // Step progress when seeds run one at a time and take long (the joint reference).
  const bool progress =
      threads == 1 && (estimators == Estimators::kJointReference || estimators == Estimators::kJointGraphReference);
  std::vector<std::vector<RobotRun>> results(num_seeds);
  ForEachSeed(num_seeds, threads,
              [&](int s) { results[s] = RunSeed(options, first_seed + s, estimators, progress, every); });

  nlohmann::json json = StartReport(options, first_seed, num_seeds, Describe(options, estimators));
  json["particles"] = options.filter.particles;
  json["scored_every_steps"] = every;
  json["filter"] = estimators == Estimators::kOwnFilter             ? options.filter.type
                   : estimators == Estimators::kJointReference      ? std::string("joint reference")
                   : estimators == Estimators::kJointGraphReference ? std::string("joint graph reference")
                                                                    : std::string("reference");
  std::printf("%-6s %-24s %10s %10s\n", "robot", "metric", "median", "p90");
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    const std::string& id = options.robots[i].id;
    for (int m = 0; m < kNumMetrics; ++m) {
      std::vector<double> values;
      values.reserve(results.size());
      for (const auto& r : results) values.push_back(Metric(r[i], m));
      const double median = evaluator::Median(values), p90 = evaluator::Percentile(values, 90.0);
      std::printf("%-6s %-24s %10.3f %10.3f\n", id.c_str(), kMetricNames[m], median, p90);
      json["robots"][id][kMetricNames[m]] = {{"median", median}, {"p90", p90}, {"values", values}};
    }
  }
  WriteJson(json, json_path);
  return 0;
}

}  // namespace mrslam::batch
