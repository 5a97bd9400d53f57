// Speed of the joint transform at a rendezvous (Google Benchmark; not a ctest test):
//  - BM_JointSmoother/K: the batch smoother's work in Cooperation::JointTransform for two
//    histories of K steps of paper_two_robots.yaml (both robots' odometry, landmark readings
//    labelled by the landmarks' identities, mutual detections from rendezvous.enable_from_step
//    on): every step added, each solve ending where the cost stops falling, solved after 5 steps, then whenever the
//    history has grown by a quarter (at least 5 steps), and at the end; then the second robot's first-pose covariance.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "robot_agent/smoother/levenberg_marquardt.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::robot_agent::smoother {
namespace {

void BM_JointSmoother(benchmark::State& state) {
  const int steps = static_cast<int>(state.range(0));
  const common::ScenarioOptions o =
      common::LoadScenario(std::string(MRSLAM_SOURCE_DIR) + "/config/paper_two_robots.yaml",
                           {"sensors.lidar.report_identity=true", "run.steps=" + std::to_string(steps)});
  const AgentOptions options = common::AgentOptionsFor(o, o.robots[0].id);
  std::map<int, BatchSmoother::Kinematics> kinematics;
  for (const auto& l : o.landmarks) {
    const bool is_static = l.motion.model == common::LandmarkMotionModel::kStatic;
    kinematics[l.id] = {is_static, l.motion.v_mps, l.motion.w_radps};
  }
  const std::unique_ptr<world_sim::StepSource> source = world_sim::MakeStepSource(o);
  std::vector<std::vector<common::SensorStep>> history;
  history.reserve(steps);
  for (int k = 0; k < steps; ++k) history.push_back(source->Step());
  const std::vector<BatchSmoother::RobotStart> starts = {{o.robots[0].id, o.robots[0].initial_pose},
                                                         {o.robots[1].id, o.robots[1].initial_pose}};
  for (auto _ : state) {
    BatchSmoother joint(options, starts, kinematics, options.rendezvous.enable_from_step);
    joint.SetRelativeCostTolerance(LeastSquares{}.min_relative_decrease);
    std::size_t next_solve = 5;
    for (std::size_t t = 0; t < history.size(); ++t) {
      joint.Add(history[t]);
      if (t + 1 == next_solve || t + 1 == history.size()) {
        joint.Solve();
        next_solve = std::max(next_solve + 5, (t + 1) * 5 / 4);
      }
    }
    benchmark::DoNotOptimize(joint.FirstPoseCovariance(1));
  }
}
BENCHMARK(BM_JointSmoother)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace mrslam::robot_agent::smoother
