#include "scripts/batch/smoother_reference.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/progress_line.h"
#include "common/se2.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "scripts/batch/batch_report.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::batch {
namespace {

// --smoother: the MAP estimate of every robot's whole path from the whole run's data (a smoother:
// each pose from every reading, also the later ones, so no filter does better on the same model),
// scored as the filters are, per robot in its own frame. Two per robot: "joint", every robot's data
// in one problem (their odometry, their readings of the landmarks and of each other from
// rendezvous.enable_from_step on; only the first robot's first pose known, the others' started
// from the truth displaced by (0.3 m, 0.3 m, 5 deg)), moved into each robot's own frame by its
// known first pose (the solution is the same up to a rigid motion whichever first pose is the
// known one); "alone", each robot's data alone. Each also with every robot's odometry factors and
// turn-rate bias estimated (BatchSmoother::EstimateOdometryCalibration). Landmark RMSE: the final
// map, all its landmarks against the truth at the last step. Solved every kSolveEveryS of run
// time (warm-started: Gauss-Newton from the dead-reckoned paths of a whole run falls into local
// minima) and at the end. "Alone, online": a causal yardstick of each robot alone, its pose at
// every step from the data up to it (its smoother's solution at the last solve, followed since by
// the odometry), scored over the run as the agents' online estimates are; its landmark figure is
// the final map's.
constexpr double kSolveEveryS = 10.0;
struct SmootherRun {
  RobotRun joint, alone, online;
  common::Pose2 joint_t_0i;  // the joint estimate's T(G_first <- G_i)
};
std::vector<SmootherRun> RunSmootherSeed(common::ScenarioOptions options, std::uint64_t seed, bool calibrate,
                                         bool progress) {
  options.seed = seed;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const auto frames = source->Truth().frames;
  const int n = static_cast<int>(options.robots.size());
  std::vector<int> all;
  std::vector<common::Pose2> guesses;
  std::vector<common::Pose2> starts;  // each robot's known first pose in its own frame
  all.reserve(n);
  starts.reserve(n);
  for (int i = 0; i < n; ++i) {
    all.push_back(i);
    starts.push_back(common::InitialPoseInOwnFrame(options.robots[i]));
    if (i > 0) guesses.push_back(FirstPoseGuess(options, frames, 0, i));
  }
  const auto statics = FieldStatics(options);
  const auto joint_ref = MakeOracleReference(options, statics, all, guesses, options.rendezvous.enable_from_step);
  robot_agent::smoother::BatchSmoother& joint = *joint_ref;
  std::vector<std::unique_ptr<robot_agent::smoother::BatchSmoother>> alone;
  alone.reserve(n);
  for (int i = 0; i < n; ++i) alone.push_back(MakeOracleReference(options, statics, {i}, {}, 0));
  if (calibrate) {
    joint.EstimateOdometryCalibration();
    for (auto& a : alone) a->EstimateOdometryCalibration();
  }
  std::vector<std::vector<common::Pose2>> truth(n);  // in each robot's own frame, steps 1..
  std::vector<std::vector<common::Pose2>> online(n, std::vector<common::Pose2>{common::Pose2{}});  // steps 0..
  common::GroundTruth last_truth;
  const int solve_every = std::max(1, static_cast<int>(std::lround(kSolveEveryS / options.run.dt_s)));
  common::ProgressLine line;
  for (int k = 1; k <= options.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    last_truth = source->Truth();
    joint.Add(steps);
    for (int i = 0; i < n; ++i) {
      alone[i]->Add({steps[i]});
      truth[i].push_back(evaluator::TruthInOwnFrame(last_truth.robots[i].pose, frames[i].second));
    }
    if (k % solve_every == 0 || k == options.run.steps) {
      joint.Solve();
      for (auto& a : alone) a->Solve();
      if (progress) {
        line.Show(std::string(calibrate ? "odometry calibrated" : "as configured") + ": step " + std::to_string(k) +
                      "/" + std::to_string(options.run.steps) + " solved",
                  k == options.run.steps);
      }
    }
    for (int i = 0; i < n; ++i) online[i].push_back(alone[i]->Pose());
  }
  std::vector<evaluator::TruePoint> true_landmarks;
  for (const auto& l : last_truth.landmarks) true_landmarks.push_back({l.pose.Translation(), std::stoi(l.id)});
  // Scores a path of robot i (steps 0..) and the final map of `reference`, moved by `to_own` into G_i.
  auto score = [&](int i, const robot_agent::smoother::BatchSmoother& reference, const common::Pose2& to_own,
                   const std::vector<common::Pose2>& path) {
    RobotRun run;
    std::vector<double> position, heading, landmark;
    for (std::size_t t = 1; t < path.size(); ++t) {
      const common::Pose2 pose = common::Compose(to_own, path[t]);
      position.push_back(evaluator::PositionError(pose, truth[i][t - 1]));
      heading.push_back(common::DegFromRad(evaluator::HeadingError(pose, truth[i][t - 1])));
    }
    std::vector<evaluator::MapPoint> map;
    for (const auto& [p, id] : reference.Landmarks()) {
      map.push_back({common::Compose(to_own, common::Pose2{p.x(), p.y(), 0.0}).Translation(), id});
    }
    const std::vector<double> errors = evaluator::LandmarkErrors(map, true_landmarks, frames[i].second);
    run.position_rmse_m = evaluator::Rmse(position);
    run.heading_rmse_deg = evaluator::Rmse(heading);
    run.landmark_rmse_m = errors.empty() ? std::nan("") : evaluator::Rmse(errors);
    run.dead_reckoning_rmse_m = std::nan("");
    return run;
  };
  std::vector<SmootherRun> out(n);
  for (int i = 0; i < n; ++i) {
    // T(G_first <- G_i): robot i's estimated first pose over its known one; its inverse is the
    // rigid motion that puts the estimate into G_i.
    out[i].joint_t_0i = common::Compose(joint.FirstPose(i), common::Inverse(starts[i]));
    out[i].joint = score(i, joint, common::Inverse(out[i].joint_t_0i), joint.Path(i));
    out[i].alone = score(i, *alone[i], common::Pose2{}, alone[i]->Path(0));
    out[i].online = score(i, *alone[i], common::Pose2{}, online[i]);
  }
  return out;
}

}  // namespace

int PrintSmoother(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                  const std::string& json_path) {
  // Task 2s + c: seed s, calibration estimated if c.
  std::vector<std::vector<SmootherRun>> results(2 * static_cast<std::size_t>(num_seeds));
  ForEachSeed(2 * num_seeds, threads, [&](int task) {
    results[task] = RunSmootherSeed(options, first_seed + task / 2, task % 2 == 1, num_seeds == 1);
  });
  nlohmann::json json =
      StartReport(options, first_seed, num_seeds, "MAP smoother of the whole run, median (p90) over seeds");
  static constexpr const char* kVariants[] = {"jointly",      "jointly, odometry calibrated",
                                              "alone",        "alone, odometry calibrated",
                                              "alone online", "alone online, odometry calibrated"};
  constexpr int kNumVariants = static_cast<int>(std::size(kVariants));
  const auto variant = [](const SmootherRun& r, int v) -> const RobotRun& {
    return v < 2 ? r.joint : v < 4 ? r.alone : r.online;
  };
  std::printf("%-6s %-17s", "robot", "metric");
  for (const char* v : kVariants) std::printf(" %28s", v);
  std::printf("\n");
  std::vector<std::vector<double>> position_medians(kNumVariants);
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    const std::string& id = options.robots[i].id;
    for (int m = 0; m < 3; ++m) {
      std::printf("%-6s %-17s", id.c_str(), kMetricNames[m]);
      for (int v = 0; v < kNumVariants; ++v) {
        std::vector<double> values;
        values.reserve(num_seeds);
        for (int s = 0; s < num_seeds; ++s) values.push_back(Metric(variant(results[2 * s + v % 2][i], v), m));
        std::printf("      %8.3f (p90 %8.3f)", evaluator::Median(values), evaluator::Percentile(values, 90.0));
        json["robots"][id][kMetricNames[m]][kVariants[v]] = values;
        if (m == 0) position_medians[v].push_back(evaluator::Median(values));
      }
      std::printf("\n");
    }
  }
  // Per seed, the joint estimate's frames (as configured): T(G_first <- G_i) per robot.
  for (int s = 0; s < num_seeds; ++s) {
    std::vector<std::array<double, 3>> frames;
    for (const SmootherRun& r : results[2 * static_cast<std::size_t>(s)]) {
      frames.push_back({r.joint_t_0i.x, r.joint_t_0i.y, r.joint_t_0i.heading});
    }
    json["joint_frames"][std::to_string(first_seed + s)] = frames;
  }
  std::printf("median over the robots of the position RMSE:");
  for (int v = 0; v < kNumVariants; ++v) {
    std::printf(" %s %.3f m%s", kVariants[v], evaluator::Median(position_medians[v]),
                v < kNumVariants - 1 ? ";" : "\n");
  }
  WriteJson(json, json_path);
  return 0;
}

}  // namespace mrslam::batch
