// Speed of map merging at a rendezvous (Google Benchmark; not a ctest test):
//  - BM_MergeLandmarks<D>: FastSlam::MergeLandmarks of a peer's map (its reported estimate, about
//    50 landmarks, moved into the own frame through an uncertain transform) into a filter of 300
//    particles that has mapped the same 50 landmarks (the ring world of fastslam_benchmark.cc,
//    no reported identities, so matching is by Mahalanobis distance), by covariance intersection.
//    The filter is copied before each merge, untimed; its blocks stay shared between the copy and
//    the original, as after resampling, so the merge pays its copy-on-write copies.
#include <cmath>
#include <optional>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/config/agent_options_projection.h"
#include "robot_agent/filters/fastslam.h"
#include "robot_agent/filters/map_fusion.h"
#include "tests/robot_agent/tiny_world.h"

namespace mrslam::robot_agent::filters {
namespace {

common::ScenarioOptions MergeScenario(robot_agent::LandmarkKinematics kinematics) {
  common::ScenarioOptions o = testing::OneRobotScenario(1.0, 0.1, 300);
  o.robots[0].initial_pose = {10.0, 0.0, common::kPi / 2};
  o.sensors.lidar.max_range_m = 6.0;
  o.sensors.lidar.report_identity = false;
  for (int i = 0; i < 50; ++i) {
    const double a = 2.0 * common::kPi * i / 50;
    testing::AddLandmark(&o, i + 1, {10.0 * std::cos(a), 10.0 * std::sin(a), 0.0});
  }
  o.filter.landmark_kinematics = kinematics;
  return o;
}

template <int D>
void BM_MergeLandmarks(benchmark::State& state, robot_agent::LandmarkKinematics kinematics) {
  const common::ScenarioOptions o = MergeScenario(kinematics);
  testing::TinyWorld world(o, 1);
  FastSlam<D> own(common::AgentOptionsFor(o, "r1"), 1), peer(common::AgentOptionsFor(o, "r1"), 2);
  // One lap and a bit (126 steps) maps every landmark in both filters.
  for (int k = 0; k < 140; ++k) {
    const common::SensorStep step = world.Step();
    own.Process(step);
    peer.Process(step);
  }
  const Eigen::Matrix3d t_covariance = Eigen::Vector3d(0.01, 0.01, 0.0004).asDiagonal();
  std::vector<MapLandmark> incoming;
  for (const MapLandmark& l : peer.Estimate().landmarks) {
    incoming.push_back(TransformLandmark(l, common::Pose2{}, t_covariance));
  }
  std::optional<FastSlam<D>> merged;
  for (auto _ : state) {
    state.PauseTiming();
    merged.emplace(own);
    state.ResumeTiming();
    benchmark::DoNotOptimize(
        merged->MergeLandmarks(incoming, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.5));
  }
  state.counters["own_landmarks"] = own.ParticleLandmarkCount(0);
  state.counters["peer_landmarks"] = static_cast<double>(incoming.size());
}
void BM_MergeLandmarksStatic(benchmark::State& state) {
  BM_MergeLandmarks<2>(state, robot_agent::LandmarkKinematics::kStatic);
}
void BM_MergeLandmarksConstantTurnRate(benchmark::State& state) {
  BM_MergeLandmarks<5>(state, robot_agent::LandmarkKinematics::kConstantTurnRate);
}
BENCHMARK(BM_MergeLandmarksStatic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MergeLandmarksConstantTurnRate)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace mrslam::robot_agent::filters
