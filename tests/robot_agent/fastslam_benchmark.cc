// Speed of the FastSLAM core (Google Benchmark; not a ctest test):
//  - BM_LandmarkUpdates/N/M: N particles x M landmarks, every landmark of every particle updated
//    once with a range-bearing measurement through UpdateBatch (load, vectorized kernel, store),
//    the path the filter takes; items_per_second = particle-landmark 2-D EKF updates per second.
//    Queued particle by particle, slot by slot, so that every whole block goes the whole-block path.
//  - BM_ContiguousUpdatesFma/N/M: a yardstick for it (same update, contiguous rows, fused
//    multiply-add); not the filter's code.
//  - BM_FullStep<D>: FastSlam::Process with 1000 particles, 50 landmarks in the map and about 10
//    detections per step (landmarks on a ring of radius 10 m, the robot driving along it with a
//    6 m lidar), for static (D = 2) and constant-turn-rate (D = 5) landmark states.
//  - BM_Estimate<D>: FastSlam::Estimate on the same world, 1000 particles (BM_EstimateAgain<D>:
//    called again on the unchanged filter).
//  - BM_MergeLandmarks<D>: merging a peer's map into a 300-particle filter on the same world.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/config/agent_options_projection.h"
#include "common/rng.h"
#include "robot_agent/filters/fastslam.h"
#include "robot_agent/filters/landmark_ekf.h"
#include "robot_agent/filters/map_fusion.h"
#include "tests/robot_agent/tiny_world.h"

// The yardstick's lane maths is inlined into it (see landmark_ekf.h): no vector argument crosses
// a call, whatever -Wpsabi reports at the end of this file.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace mrslam::robot_agent::filters {
namespace {

void BM_LandmarkUpdates(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int m = static_cast<int>(state.range(1));
  const int blocks_per_particle = (m + kLanes - 1) / kLanes;
  common::Rng rng(1, "benchmark");
  std::vector<LandmarkBlock<2>> blocks(static_cast<std::size_t>(n) * blocks_per_particle);
  std::vector<common::Pose2> poses(n);
  std::vector<double> z_r(static_cast<std::size_t>(n) * m), z_b(z_r.size());
  for (int p = 0; p < n; ++p) {
    poses[p] = {rng.Normal(0.0, 0.1), rng.Normal(0.0, 0.1), rng.Normal(0.0, 0.05)};
    for (int j = 0; j < m; ++j) {
      const double r = rng.Uniform(0.5, 6.0), a = rng.Uniform(-common::kPi, common::kPi);
      StateMatrix<2> cov;
      cov << 0.02, 0.003, 0.003, 0.03;
      blocks[p * blocks_per_particle + j / kLanes].Set(j % kLanes, StateVector<2>(r * std::cos(a), r * std::sin(a)),
                                                       cov);
      z_r[p * m + j] = r + rng.Normal(0.0, 0.03);
      z_b[p * m + j] = common::WrapAngle(a + rng.Normal(0.0, 0.03));
    }
  }
  UpdateBatch<2> batch(0.03 * 0.03, 0.03 * 0.03);
  for (auto _ : state) {
    for (int p = 0; p < n; ++p) {
      for (int j = 0; j < m; ++j) {
        batch.Add(&blocks[p * blocks_per_particle + j / kLanes], j % kLanes, poses[p], z_r[p * m + j], z_b[p * m + j]);
      }
    }
    batch.Run();
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n * m);
}
BENCHMARK(BM_LandmarkUpdates)->ArgsProduct({{100, 1000, 10000}, {2, 50, 500}})->Unit(benchmark::kMillisecond);

#if defined(__x86_64__)
// A yardstick only, not the filter's path: the same update (EkfUpdate, D = 2) over contiguous
// rows, one array per field and input, eight lanes per AVX-512 instruction, with fused
// multiply-add (this file is not compiled with -ffp-contract=off). Its numbers depend on the CPU.
__attribute__((target("avx512f,fma"))) void ContiguousUpdatesFma(double* const* state, const double* const* in, int n,
                                                                 double var) {
  for (int k = 0; k < n; k += 8) {
    Double8 s[5], z[5];
    for (int f = 0; f < 5; ++f) std::memcpy(&s[f], state[f] + k, sizeof(Double8));
    for (int i = 0; i < 5; ++i) std::memcpy(&z[i], in[i] + k, sizeof(Double8));
    EkfUpdate<Double8, 2>(s, s + 2, z[0], z[1], z[2], z[3], z[4], var, var);
    for (int f = 0; f < 5; ++f) std::memcpy(state[f] + k, &s[f], sizeof(Double8));
  }
}

// BM_ContiguousUpdatesFma/N/M: the yardstick above over the N x M updates of BM_LandmarkUpdates
// (M rounded up to a multiple of 8); items_per_second as there.
void BM_ContiguousUpdatesFma(benchmark::State& state) {
  if (!__builtin_cpu_supports("avx512f")) {
    state.SkipWithError("no AVX-512F");
    return;
  }
  const int n = static_cast<int>(state.range(0));
  const int m = static_cast<int>(state.range(1));
  const int total = n * ((m + 7) / 8 * 8);
  common::Rng rng(1, "benchmark");
  std::vector<std::vector<double>> rows(10, std::vector<double>(total));
  for (int k = 0; k < total; ++k) {
    const double r = rng.Uniform(0.5, 6.0), a = rng.Uniform(-common::kPi, common::kPi);
    rows[0][k] = r * std::cos(a);
    rows[1][k] = r * std::sin(a);
    rows[2][k] = 0.02;
    rows[3][k] = 0.003;
    rows[4][k] = 0.03;
    rows[5][k] = rng.Normal(0.0, 0.1);
    rows[6][k] = rng.Normal(0.0, 0.1);
    rows[7][k] = rng.Normal(0.0, 0.05);
    rows[8][k] = r + rng.Normal(0.0, 0.03);
    rows[9][k] = common::WrapAngle(a + rows[7][k] + rng.Normal(0.0, 0.03));
  }
  double* fields[5];
  const double* in[5];
  for (int i = 0; i < 5; ++i) {
    fields[i] = rows[i].data();
    in[i] = rows[5 + i].data();
  }
  for (auto _ : state) {
    ContiguousUpdatesFma(fields, in, total, 0.03 * 0.03);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n * m);
}
BENCHMARK(BM_ContiguousUpdatesFma)->Args({1000, 50})->Unit(benchmark::kMillisecond);
#endif

common::ScenarioOptions RingScenario(robot_agent::LandmarkKinematics kinematics, int particles) {
  common::ScenarioOptions o = testing::OneRobotScenario(1.0, 0.1, particles);
  o.run.dt_s = 0.5;
  o.robots[0].initial_pose = {10.0, 0.0, common::kPi / 2};
  o.sensors.lidar.max_range_m = 6.0;
  for (int i = 0; i < 50; ++i) {
    const double a = 2.0 * common::kPi * i / 50;
    testing::AddLandmark(&o, i + 1, {10.0 * std::cos(a), 10.0 * std::sin(a), 0.0});
  }
  o.filter.landmark_kinematics = kinematics;
  return o;
}

// The ring world and a filter of the given seed that has driven `steps` steps in it (one lap,
// 126 steps, maps every landmark).
template <int D>
struct RingRun {
  RingRun(robot_agent::LandmarkKinematics kinematics, int particles, int steps, std::uint64_t filter_seed)
      : options(RingScenario(kinematics, particles)),
        world(options, 1),
        filter(common::AgentOptionsFor(options, "r1"), filter_seed) {
    for (int k = 0; k < steps; ++k) filter.Process(world.Step());
  }
  common::ScenarioOptions options;
  testing::TinyWorld world;
  FastSlam<D> filter;
};

template <int D>
void BM_FullStep(benchmark::State& state, robot_agent::LandmarkKinematics kinematics) {
  // One lap maps every landmark; then the steps to time are prepared in advance.
  RingRun<D> run(kinematics, 1000, 130, 1);
  testing::TinyWorld& world = run.world;
  FastSlam<D>& filter = run.filter;
  std::vector<common::SensorStep> steps;
  double detections = 0.0;
  for (int k = 0; k < 64; ++k) {
    steps.push_back(world.Step());
    detections += steps.back().lidar.landmarks.size();
  }
  std::size_t next = 0;
  for (auto _ : state) {
    filter.Process(steps[next]);
    if (++next == steps.size()) {  // the world moves on: prepare the next steps untimed
      state.PauseTiming();
      for (auto& s : steps) s = world.Step();
      next = 0;
      state.ResumeTiming();
    }
  }
  state.counters["landmarks"] = filter.ParticleLandmarkCount(0);
  state.counters["detections_per_step"] = detections / 64.0;
  state.counters["steps_per_second"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
void BM_FullStepStatic(benchmark::State& state) { BM_FullStep<2>(state, robot_agent::LandmarkKinematics::kStatic); }
void BM_FullStepConstantTurnRate(benchmark::State& state) {
  BM_FullStep<5>(state, robot_agent::LandmarkKinematics::kConstantTurnRate);
}
BENCHMARK(BM_FullStepStatic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FullStepConstantTurnRate)->Unit(benchmark::kMillisecond);

// FastSlam::Estimate (the reported map over all particles) after the world has moved on 64
// steps past the first lap, as the agent calls it once per step: each time on a fresh copy of
// the filter (copied untimed), which computes the map. BM_EstimateAgain<D>: a further call on an
// unchanged filter, which returns the map kept since the first (as when the agent applies a
// peer's snapshot between steps).
template <int D>
void BM_Estimate(benchmark::State& state, robot_agent::LandmarkKinematics kinematics, bool again) {
  const RingRun<D> run(kinematics, 1000, 194, 1);
  std::optional<FastSlam<D>> copy;
  if (again) copy.emplace(run.filter);
  for (auto _ : state) {
    if (!again) {
      state.PauseTiming();
      copy.emplace(run.filter);
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(copy->Estimate());
  }
  state.counters["landmarks"] = static_cast<double>(run.filter.Estimate().landmarks.size());
}
void BM_EstimateStatic(benchmark::State& state) {
  BM_Estimate<2>(state, robot_agent::LandmarkKinematics::kStatic, false);
}
void BM_EstimateConstantTurnRate(benchmark::State& state) {
  BM_Estimate<5>(state, robot_agent::LandmarkKinematics::kConstantTurnRate, false);
}
void BM_EstimateAgainStatic(benchmark::State& state) {
  BM_Estimate<2>(state, robot_agent::LandmarkKinematics::kStatic, true);
}
void BM_EstimateAgainConstantTurnRate(benchmark::State& state) {
  BM_Estimate<5>(state, robot_agent::LandmarkKinematics::kConstantTurnRate, true);
}
BENCHMARK(BM_EstimateStatic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EstimateConstantTurnRate)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EstimateAgainStatic)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EstimateAgainConstantTurnRate)->Unit(benchmark::kMillisecond);

// FastSlam::MergeLandmarks of a peer's map (its reported estimate, about 50 landmarks, moved into
// the own frame through an uncertain transform) into a filter of 300 particles that has mapped
// the same 50 landmarks (no reported identities: matching by Mahalanobis distance), by
// covariance intersection. The filter is copied before each merge, untimed; its blocks stay
// shared between the copy and the original, as after resampling, so the merge pays its
// copy-on-write copies.
template <int D>
void BM_MergeLandmarks(benchmark::State& state, robot_agent::LandmarkKinematics kinematics) {
  // Two filters of 300 particles over the same 140 steps of the ring world.
  const RingRun<D> own_run(kinematics, 300, 140, 1), peer_run(kinematics, 300, 140, 2);
  const FastSlam<D>& own = own_run.filter;
  const Eigen::Matrix3d t_covariance = Eigen::Vector3d(0.01, 0.01, 0.0004).asDiagonal();
  std::vector<MapLandmark> incoming;
  for (const MapLandmark& l : peer_run.filter.Estimate().landmarks) {
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

BENCHMARK_MAIN();
