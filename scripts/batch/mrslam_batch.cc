// mrslam_batch: the accuracy of each robot's own filter over many seeds, in-process (the World or
// a data set's replay, and one filter per robot, no DDS). For every seed it runs the scenario to its end and computes
// per robot (docs/metrics.md's definitions, in the robot's own frame):
//   position RMSE (m) and heading RMSE (deg) over every step,
//   landmark RMSE (m): root of the mean over every step and every landmark in the map of the
//     squared error against the true landmark it stands for (LandmarkErrors),
//   dead-reckoning RMSE (m): odometry integrated from the known initial pose.
// Prints the median and 90th percentile over seeds per robot, optionally writes them (and the
// per-seed values) as JSON. Progress goes to stderr. With --reference, the approximately ideal
// filter (BatchSmoother: batch MAP with oracle association and kinematics) replaces each robot's
// own filter, on the same data (the lidar reports identities; nothing else changes). With
// --transform-reference it prints instead, per ordered pair of robots, the error of the transform
// T(G_i <- G_j) at the end of their first encounter (docs/cooperation.md) as the joint MAP reference of
// both robots holds it: the best that "everything both robots know" allows (with a
// landmark_field, from its static landmarks: the movers' readings are left out). The JSON also
// holds each met pair's transform per seed.
//
//   mrslam_batch --scenario FILE --seeds A..B [--set k=v]... [--particles N] [--threads T]
//                [--reference | --transform-reference] [--json FILE]
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/progress_line.h"
#include "common/se2.h"
#include "robot_agent/filters/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/core/world.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/evaluator/robot_scorer.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam {
namespace {

// The metrics of one robot in one run.
struct RobotRun {
  double position_rmse_m = 0.0;
  double heading_rmse_deg = 0.0;
  double landmark_rmse_m = 0.0;
  double dead_reckoning_rmse_m = 0.0;
};

constexpr const char* kMetricNames[] = {"position_rmse_m", "heading_rmse_deg", "landmark_rmse_m",
                                        "dead_reckoning_rmse_m"};
double Metric(const RobotRun& r, int i) {
  switch (i) {
    case 0:
      return r.position_rmse_m;
    case 1:
      return r.heading_rmse_deg;
    case 2:
      return r.landmark_rmse_m;
    default:
      return r.dead_reckoning_rmse_m;
  }
}

// Parses "A..B" (or "A") into an inclusive range.
std::pair<std::uint64_t, std::uint64_t> ParseSeeds(const std::string& text) {
  const std::size_t dots = text.find("..");
  try {
    if (dots == std::string::npos) {
      const std::uint64_t s = std::stoull(text);
      return {s, s};
    }
    const std::uint64_t a = std::stoull(text.substr(0, dots));
    const std::uint64_t b = std::stoull(text.substr(dots + 2));
    if (b < a) throw std::invalid_argument("empty");
    return {a, b};
  } catch (const std::exception&) {
    throw std::runtime_error("--seeds must be A..B with A <= B, not '" + text + "'");
  }
}

// One robot's estimator in a run: its own filter, or the reference.
class Estimator {
 public:
  Estimator(const common::ScenarioOptions& options, int robot_index, std::uint64_t seed, bool reference) {
    if (reference) {
      reference_ =
          std::make_unique<robot_agent::smoother::BatchSmoother>(batch::OracleSmoother(options, {robot_index}));
    } else {
      filter_ =
          robot_agent::filters::CreateFilter(common::AgentOptionsFor(options, options.robots[robot_index].id), seed);
      if (!filter_) throw std::runtime_error("filter.type " + options.filter.type + " is not implemented");
    }
  }
  void Process(const common::SensorStep& step) {
    if (filter_) {
      filter_->Process(step);
    } else {
      reference_->Process(step);
    }
  }
  // The current pose and map (landmark positions with their identities).
  struct Output {
    common::Pose2 pose;
    std::optional<Eigen::Matrix3d> covariance;  // none from the reference
    std::vector<evaluator::MapPoint> map;
  };
  Output Estimate() const {
    Output out;
    if (filter_) {
      const robot_agent::filters::FilterEstimate e = filter_->Estimate();
      out.pose = e.pose;
      out.covariance = e.covariance;
      for (const auto& l : e.landmarks) out.map.push_back({l.mean.head<2>(), l.landmark_id});
    } else {
      out.pose = reference_->Pose();
      for (const auto& [position, id] : reference_->Landmarks()) out.map.push_back({position, id});
    }
    return out;
  }

 private:
  std::unique_ptr<robot_agent::filters::SlamFilter> filter_;
  std::unique_ptr<robot_agent::smoother::BatchSmoother> reference_;
};

// Runs one seed: the scenario's step source (the simulated World, or the replay of a recorded data
// set) + one estimator per robot, each scored as the evaluator scores it (RobotScorer); returns the
// metrics per robot (scenario order).
std::vector<RobotRun> RunSeed(common::ScenarioOptions options, std::uint64_t seed, bool reference) {
  options.seed = seed;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const common::GroundTruth truth0 = source->Truth();
  const std::size_t n = options.robots.size();
  std::vector<Estimator> estimators;
  std::vector<evaluator::RobotScorer> scorers;
  for (std::size_t i = 0; i < n; ++i) {
    estimators.emplace_back(options, static_cast<int>(i), seed, reference);
    const common::Pose2& frame = truth0.frames[i].second;
    scorers.emplace_back(frame, evaluator::TruthInOwnFrame(truth0.robots[i].pose, frame), options.sensors.lidar);
  }
  for (int k = 0; k < options.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    const common::GroundTruth truth = source->Truth();
    for (std::size_t i = 0; i < n; ++i) {
      estimators[i].Process(steps[i]);
      const Estimator::Output e = estimators[i].Estimate();
      scorers[i].Add(truth, truth.robots[i].pose, e.pose, e.covariance, e.map, &steps[i].odometry);
    }
  }
  std::vector<RobotRun> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const evaluator::RobotSummary s = scorers[i].Summary();
    out[i] = {s.position_rmse_m, s.heading_rmse_deg, s.landmark_rmse_m, s.dead_reckoning_rmse_m};
  }
  return out;
}

// The error of a held transform against the true one (translation in the holder's frame).
struct TransformError {
  double m = std::nan(""), deg = std::nan("");
};
TransformError ErrorOf(const common::Pose2& held, const common::Pose2& truth) {
  return {(held.Translation() - truth.Translation()).norm(),
          common::DegFromRad(std::abs(common::WrapAngle(held.heading - truth.heading)))};
}

// The transform errors of one pair (i, j) in one seed at the end of their first encounter (the
// detector's rule: both detections within rendezvous.window_steps, from
// rendezvous.enable_from_step on; the end: the last step of the run of consecutive steps with
// mutual detections, at most 10 steps), for T(G_i <- G_j) and T(G_j <- G_i):
//  - joint: as the joint MAP reference of both robots holds it. It counts their detections of
//    each other from enable_from_step on, and starts robot j's first pose from the truth
//    displaced by (0.3 m, 0.3 m, 5 deg): a result near that displacement would say the data do
//    not place it;
//  - own: each robot's own MAP reference estimate composed with the exact relative pose of the
//    two robots at that step (a perfect mutual measurement).
// NaN if they never meet.
struct PairErrors {
  TransformError joint_ij, joint_ji, own_ij, own_ji;
  common::Pose2 joint_t_ij;  // the joint reference's T(G_i <- G_j) (when they met)
};

// The MAP reference of the robots (scenario indices; the first at its known first pose, the
// others started from the guesses). With a landmark_field it knows the field's static landmarks
// only (field_statics, from FieldStatics) and leaves the readings of its movers out: they shuttle
// back and forth, a motion the reference does not model.
using Kinematics = std::map<int, robot_agent::smoother::BatchSmoother::Kinematics>;
std::optional<Kinematics> FieldStatics(const common::ScenarioOptions& options) {
  if (!options.landmark_field.enabled) return std::nullopt;
  Kinematics statics;
  for (const auto& l : world_sim::ExpandLandmarks(options)) {
    if (l.motion.model == common::LandmarkMotionModel::kStatic) statics[l.id] = {};
  }
  return statics;
}
std::unique_ptr<robot_agent::smoother::BatchSmoother> MakeReference(const common::ScenarioOptions& options,
                                                                    const std::optional<Kinematics>& field_statics,
                                                                    const std::vector<int>& robots,
                                                                    const std::vector<common::Pose2>& guesses,
                                                                    int from_step) {
  using robot_agent::smoother::BatchSmoother;
  if (!field_statics)
    return std::make_unique<BatchSmoother>(batch::OracleSmoother(options, robots, guesses, from_step));
  return std::make_unique<BatchSmoother>(common::AgentOptionsFor(options, options.robots.at(robots.front()).id),
                                         batch::OracleStarts(options, robots, guesses), *field_statics, from_step);
}

PairErrors RunTransformSeed(common::ScenarioOptions options, std::uint64_t seed, int i, int j) {
  options.seed = seed;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const auto frames = source->Truth().frames;
  const common::Pose2 true_ij = common::Between(frames[i].second, frames[j].second);
  // T(G_i <- G_j) maps j's first pose in G_j to its first pose in G_i.
  const common::Pose2 start_j = common::InitialPoseInOwnFrame(options.robots[j]);
  const common::Pose2 guess = common::Compose(common::Compose(true_ij, start_j), {0.3, 0.3, common::kPi / 36});
  const std::optional<Kinematics> statics = FieldStatics(options);
  const auto joint_ref = MakeReference(options, statics, {i, j}, {guess}, options.rendezvous.enable_from_step);
  const auto own_i_ref = MakeReference(options, statics, {i}, {}, 0);
  const auto own_j_ref = MakeReference(options, statics, {j}, {}, 0);
  robot_agent::smoother::BatchSmoother &joint = *joint_ref, &own_i = *own_i_ref, &own_j = *own_j_ref;
  const std::string& id_i = options.robots[i].id;
  const std::string& id_j = options.robots[j].id;
  auto sees = [](const common::SensorStep& step, const std::string& id) {
    return std::any_of(step.lidar.robots.begin(), step.lidar.robots.end(),
                       [&](const common::RobotDetection& d) { return d.seen_robot_id == id; });
  };
  int last_ij = -1000000, last_ji = -1000000, fired = -1;
  common::Pose2 held_joint, held_own;
  PairErrors out;
  for (int k = 1; k <= options.run.steps; ++k) {
    const std::vector<common::SensorStep> steps = source->Step();
    joint.Process({steps[i], steps[j]});
    own_i.Process(steps[i]);
    own_j.Process(steps[j]);
    const bool ij = sees(steps[i], id_j), ji = sees(steps[j], id_i);
    if (ij) last_ij = k;
    if (ji) last_ji = k;
    const int w = options.rendezvous.window_steps;
    if (fired < 0 && k >= options.rendezvous.enable_from_step && last_ij > k - w && last_ji > k - w) fired = k;
    if (fired < 0) continue;
    const bool in_run = k == fired || (ij && ji && k - fired < 10);
    if (in_run) {
      const common::GroundTruth truth = source->Truth();
      const common::Pose2 relative = common::Between(truth.robots[i].pose, truth.robots[j].pose);
      held_joint = common::Compose(joint.FirstPose(1), common::Inverse(start_j));
      held_own = common::Compose(common::Compose(own_i.Pose(), relative), common::Inverse(own_j.Pose()));
    }
    if (!in_run || k == options.run.steps) {
      const common::Pose2 true_ji = common::Inverse(true_ij);
      out = {ErrorOf(held_joint, true_ij), ErrorOf(common::Inverse(held_joint), true_ji), ErrorOf(held_own, true_ij),
             ErrorOf(common::Inverse(held_own), true_ji), held_joint};
      break;
    }
  }
  return out;
}

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
// minima) and at the end.
constexpr double kSolveEveryS = 10.0;
struct SmootherRun {
  RobotRun joint, alone;
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
    if (i == 0) continue;
    const common::Pose2 true_0i = common::Between(frames[0].second, frames[i].second);
    guesses.push_back(common::Compose(common::Compose(true_0i, starts[i]), {0.3, 0.3, common::kPi / 36}));
  }
  const std::optional<Kinematics> statics = FieldStatics(options);
  const auto joint_ref = MakeReference(options, statics, all, guesses, options.rendezvous.enable_from_step);
  robot_agent::smoother::BatchSmoother& joint = *joint_ref;
  std::vector<std::unique_ptr<robot_agent::smoother::BatchSmoother>> alone;
  alone.reserve(n);
  for (int i = 0; i < n; ++i) alone.push_back(MakeReference(options, statics, {i}, {}, 0));
  if (calibrate) {
    joint.EstimateOdometryCalibration();
    for (auto& a : alone) a->EstimateOdometryCalibration();
  }
  std::vector<std::vector<common::Pose2>> truth(n);  // in each robot's own frame, steps 1..
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
  }
  std::vector<evaluator::TruePoint> true_landmarks;
  for (const auto& l : last_truth.landmarks) true_landmarks.push_back({l.pose.Translation(), std::stoi(l.id)});
  // Scores robot i's path of `reference` (robot r of its set), moved by `to_own` into G_i.
  auto score = [&](int i, const robot_agent::smoother::BatchSmoother& reference, int r, const common::Pose2& to_own) {
    RobotRun run;
    std::vector<double> position, heading, landmark;
    const std::vector<common::Pose2>& path = reference.Path(r);
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
    out[i].joint = score(i, joint, i, common::Inverse(out[i].joint_t_0i));
    out[i].alone = score(i, *alone[i], 0, common::Pose2{});
  }
  return out;
}

// Runs fn(s) for s in [0, num_seeds) on `threads` worker threads taking seeds from a shared
// counter, with progress on stderr; the first error stops the others and is rethrown.
template <typename Fn>
void ForEachSeed(int num_seeds, int threads, const Fn& fn) {
  std::atomic<int> next{0};
  std::atomic<int> done{0};
  std::mutex error_mutex;
  std::string error;
  common::ProgressLine progress;
  auto worker = [&]() {
    for (int s = next++; s < num_seeds; s = next++) {
      try {
        fn(s);
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        error = e.what();
        next = num_seeds;
        return;
      }
      const int d = ++done;
      const std::lock_guard<std::mutex> lock(error_mutex);
      progress.Show("seeds done: " + std::to_string(d) + "/" + std::to_string(num_seeds), d == num_seeds);
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(std::min(threads, num_seeds));
  for (int t = 0; t < std::min(threads, num_seeds); ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  progress.Finish();
  if (!error.empty()) throw std::runtime_error(error);
}

// Prints the first line of a report ("scenario NAME, seeds A..B, WHAT") and returns the report's
// JSON with the scenario and the seeds.
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

// --transform-reference: per ordered pair, median and 90th percentile over the seeds where the
// pair met.
int PrintTransformReference(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds,
                            int threads, const std::string& json_path) {
  const int n = static_cast<int>(options.robots.size());
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) pairs.emplace_back(i, j);
  }
  std::vector<std::vector<PairErrors>> results(num_seeds);
  ForEachSeed(num_seeds, threads, [&](int s) {
    for (const auto& [i, j] : pairs) results[s].push_back(RunTransformSeed(options, first_seed + s, i, j));
  });
  nlohmann::json json =
      StartReport(options, first_seed, num_seeds, "transform at the end of the first encounter, joint MAP reference");
  std::printf("%-12s %5s  %-31s  %s\n", "holder<-peer", "met", "joint reference: m / deg (p90)",
              "own references + exact mutual: m / deg (p90)");
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    for (const bool forward : {true, false}) {
      const std::string& a = options.robots[forward ? pairs[p].first : pairs[p].second].id;
      const std::string& b = options.robots[forward ? pairs[p].second : pairs[p].first].id;
      std::vector<double> joint_m, joint_deg, own_m, own_deg;
      std::vector<std::uint64_t> met_seeds;
      std::vector<std::array<double, 3>> joint_t;  // T(G_a <- G_b) per seed met
      for (std::size_t s = 0; s < results.size(); ++s) {
        const auto& r = results[s];
        const TransformError& joint = forward ? r[p].joint_ij : r[p].joint_ji;
        const TransformError& own = forward ? r[p].own_ij : r[p].own_ji;
        if (std::isnan(joint.m)) continue;
        met_seeds.push_back(first_seed + s);
        const common::Pose2 t = forward ? r[p].joint_t_ij : common::Inverse(r[p].joint_t_ij);
        joint_t.push_back({t.x, t.y, t.heading});
        joint_m.push_back(joint.m);
        joint_deg.push_back(joint.deg);
        own_m.push_back(own.m);
        own_deg.push_back(own.deg);
      }
      std::string name = a;
      name.append("<-").append(b);
      if (joint_m.empty()) {
        std::printf("%-12s %5d\n", name.c_str(), 0);
        continue;
      }
      std::printf("%-12s %5zu  %5.3f / %4.2f (%5.3f / %5.2f)  %5.3f / %4.2f (%5.3f / %5.2f)\n", name.c_str(),
                  joint_m.size(), evaluator::Median(joint_m), evaluator::Median(joint_deg),
                  evaluator::Percentile(joint_m, 90.0), evaluator::Percentile(joint_deg, 90.0),
                  evaluator::Median(own_m), evaluator::Median(own_deg), evaluator::Percentile(own_m, 90.0),
                  evaluator::Percentile(own_deg, 90.0));
      json["pairs"][name] = {{"seeds", met_seeds},           {"joint_transform", joint_t}, {"joint_error_m", joint_m},
                             {"joint_error_deg", joint_deg}, {"own_error_m", own_m},       {"own_error_deg", own_deg}};
    }
  }
  WriteJson(json, json_path);
  return 0;
}

// --smoother: per robot, median and 90th percentile over the seeds, joint and alone, with the
// configured odometry calibration and with it estimated; the JSON also gets, per seed, every
// robot's frame as the joint estimate (as configured) places it in the first robot's frame.
int PrintSmoother(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                  const std::string& json_path) {
  // Task 2s + c: seed s, calibration estimated if c.
  std::vector<std::vector<SmootherRun>> results(2 * static_cast<std::size_t>(num_seeds));
  ForEachSeed(2 * num_seeds, threads, [&](int task) {
    results[task] = RunSmootherSeed(options, first_seed + task / 2, task % 2 == 1, num_seeds == 1);
  });
  nlohmann::json json =
      StartReport(options, first_seed, num_seeds, "MAP smoother of the whole run, median (p90) over seeds");
  const char* kVariants[] = {"jointly", "jointly, odometry calibrated", "alone", "alone, odometry calibrated"};
  std::printf("%-6s %-17s", "robot", "metric");
  for (const char* v : kVariants) std::printf(" %28s", v);
  std::printf("\n");
  std::vector<std::vector<double>> position_medians(4);
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    const std::string& id = options.robots[i].id;
    for (int m = 0; m < 3; ++m) {
      std::printf("%-6s %-17s", id.c_str(), kMetricNames[m]);
      for (int v = 0; v < 4; ++v) {
        std::vector<double> values;
        for (int s = 0; s < num_seeds; ++s) {
          const SmootherRun& r = results[2 * s + v % 2][i];
          values.push_back(Metric(v < 2 ? r.joint : r.alone, m));
        }
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
  for (int v = 0; v < 4; ++v)
    std::printf(" %s %.3f m%s", kVariants[v], evaluator::Median(position_medians[v]), v < 3 ? ";" : "\n");
  WriteJson(json, json_path);
  return 0;
}

int Main(int argc, char** argv) {
  CLI::App app{"Accuracy of each robot's own filter over seeds (in-process, no DDS)."};
  std::string scenario_path, seeds_text = "1..50", json_path;
  std::vector<std::string> overrides;
  int particles = 0, threads = 1;
  bool reference = false, transform_reference = false, smoother = false;
  app.add_option("--scenario", scenario_path, "Scenario YAML file")->required();
  app.add_option("--seeds", seeds_text, "Seed range A..B (inclusive)");
  app.add_option("--set", overrides, "Override a scenario key: key.path=value (repeatable)");
  app.add_option("--particles", particles, "Particles per filter (overrides filter.particles)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--threads", threads, "Seeds run in parallel")->check(CLI::Range(1, 256));
  app.add_flag("--reference", reference,
               "Run the approximately ideal reference instead of the filter: the batch MAP estimate of the "
               "path so far at every step, with oracle association and landmark kinematics (static or "
               "unicycle landmarks)");
  app.add_flag("--transform-reference", transform_reference,
               "Print instead the error of each pair's transform at the end of its first encounter as the "
               "joint MAP reference of both robots holds it");
  app.add_flag("--smoother", smoother,
               "Print instead each robot's error under the MAP smoother of the whole run: all robots' data "
               "jointly (only the first robot's start known) and each robot's data alone");
  app.add_option("--json", json_path, "Write medians, 90th percentiles and per-seed values here");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  const auto [first_seed, last_seed] = ParseSeeds(seeds_text);
  common::ScenarioOptions options = common::LoadScenario(scenario_path, overrides);
  if (particles > 0) options.filter.particles = particles;
  if (static_cast<int>(reference) + static_cast<int>(transform_reference) + static_cast<int>(smoother) > 1) {
    throw std::runtime_error("one of --reference, --transform-reference and --smoother at most");
  }
  // The reference's oracle association: the same detections, with their identities.
  if (reference || transform_reference || smoother) options.sensors.lidar.report_identity = true;
  const int num_seeds = static_cast<int>(last_seed - first_seed + 1);

  if (transform_reference) return PrintTransformReference(options, first_seed, num_seeds, threads, json_path);
  if (smoother) return PrintSmoother(options, first_seed, num_seeds, threads, json_path);
  std::vector<std::vector<RobotRun>> results(num_seeds);
  const std::uint64_t first = first_seed;  // a structured binding is not captured before C++20
  ForEachSeed(num_seeds, threads, [&](int s) { results[s] = RunSeed(options, first + s, reference); });

  const std::string estimator =
      reference ? std::string("the MAP reference")
                : options.filter.type + " with " + std::to_string(options.filter.particles) + " particles";
  nlohmann::json json = StartReport(options, first_seed, num_seeds, estimator);
  json["particles"] = options.filter.particles;
  json["filter"] = reference ? std::string("reference") : options.filter.type;
  std::printf("%-6s %-24s %10s %10s\n", "robot", "metric", "median", "p90");
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    const std::string& id = options.robots[i].id;
    for (int m = 0; m < 4; ++m) {
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

}  // namespace
}  // namespace mrslam

int main(int argc, char** argv) {
  try {
    return mrslam::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mrslam_batch: error: %s\n", e.what());
    return 1;
  }
}
