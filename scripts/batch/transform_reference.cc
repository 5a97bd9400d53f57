#include "scripts/batch/transform_reference.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "common/se2.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "scripts/batch/batch_report.h"
#include "scripts/batch/oracle_reference.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::batch {
namespace {

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

PairErrors RunTransformSeed(common::ScenarioOptions options, std::uint64_t seed, int i, int j) {
  options.seed = seed;
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(options);
  const auto frames = source->Truth().frames;
  const common::Pose2 true_ij = common::Between(frames[i].second, frames[j].second);
  // T(G_i <- G_j) maps j's first pose in G_j to its first pose in G_i.
  const common::Pose2 start_j = common::InitialPoseInOwnFrame(options.robots[j]);
  const common::Pose2 guess = FirstPoseGuess(options, frames, i, j);
  const auto statics = FieldStatics(options);
  const auto joint_ref = MakeOracleReference(options, statics, {i, j}, {guess}, options.rendezvous.enable_from_step);
  const auto own_i_ref = MakeOracleReference(options, statics, {i}, {}, 0);
  const auto own_j_ref = MakeOracleReference(options, statics, {j}, {}, 0);
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

}  // namespace

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

}  // namespace mrslam::batch
