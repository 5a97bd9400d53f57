// evaluator: the only process besides world_sim that reads the truth. Scores every robot's
// estimates in its own frame and writes metrics.csv, summary.json, TUM trajectories, tracks.csv and view.jsonl.
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/spdlog.h>

#include "common/app.h"
#include "common/config/scenario_flags.h"
#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "common/dds/process_exit.h"
#include "common/logging.h"
#include "mrslamPubSubTypes.h"
#include "world_sim/evaluator/estimate_msg.h"
#include "world_sim/evaluator/run_evaluator.h"

namespace mrslam::evaluator {
namespace {

// A chunk of a robot's final trajectory, or an empty message why it is rejected.
std::string FinalChunkProblem(const msg::FinalTrajectory& m) {
  if (m.chunks() == 0 || m.chunks() > 100000 || m.chunk() >= m.chunks()) return "chunk index out of range";
  if (m.poses().size() > 1000) return "more than 1000 poses";
  for (const auto& p : m.poses()) {
    if (!std::isfinite(p.time_s()) || !std::isfinite(p.pose().x_m()) || !std::isfinite(p.pose().y_m()) ||
        !std::isfinite(p.pose().heading_rad()))
      return "a pose that is not finite";
  }
  return {};
}

std::vector<FinalPose> FromFinalMsg(const msg::FinalTrajectory& m) {
  std::vector<FinalPose> out;
  out.reserve(m.poses().size());
  for (const auto& p : m.poses()) out.push_back({p.step(), p.time_s(), dds::FromMsg(p.pose())});
  return out;
}

// Owns the participant and readers; feeds the RunEvaluator until the run is complete.
int Evaluate(const common::ScenarioOptions& scenario, const dds::ParticipantOptions& dds_options,
             const std::string& out_dir, const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  // Each wake-up costs a context switch; on MRCLAM's --shm replay some 1,600 samples a second
  // arrive (five robots' estimates and sensor steps, the truth).
  constexpr auto kGather = std::chrono::milliseconds(5);
  const auto start = Clock::now();
  dds::Participant participant(dds_options);
  dds::Notifier notifier;
  dds::Reader<msg::GroundTruthPubSubType> truth_reader(participant, dds::kTruthTopic, &notifier);
  std::map<std::string, std::unique_ptr<dds::Reader<msg::EstimatePubSubType>>> estimate_readers;
  // Each robot's sensor steps, for the odometry (dead reckoning) and when the robot's data left.
  std::map<std::string, std::unique_ptr<dds::Reader<msg::SensorStepPubSubType>>> sensor_readers;
  std::map<std::string, std::unique_ptr<dds::Reader<msg::FinalTrajectoryPubSubType>>> final_readers;
  for (const auto& r : scenario.robots) {
    estimate_readers[r.id] =
        std::make_unique<dds::Reader<msg::EstimatePubSubType>>(participant, dds::EstimateTopic(r.id), &notifier);
    sensor_readers[r.id] =
        std::make_unique<dds::Reader<msg::SensorStepPubSubType>>(participant, dds::SensorTopic(r.id), &notifier);
    final_readers[r.id] = std::make_unique<dds::Reader<msg::FinalTrajectoryPubSubType>>(
        participant, dds::FinalTrajectoryTopic(r.id), &notifier);
  }
  RunEvaluator evaluator(scenario, out_dir);
  std::uint64_t seen = 0;
  // The run is gone when nothing new (a message not taken in yet) arrives for this long: samples
  // that are sent again (a writer's history replayed to the evaluator) do not count.
  auto last_new = Clock::now();
  std::size_t taken = 0;
  const auto timeout = std::chrono::duration<double>(scenario.run.ack_timeout_s * 2.0);
  spdlog::info("evaluating '{}' seed {} on domain {}", scenario.name, scenario.seed, dds_options.domain);
  while (!evaluator.Complete()) {
    if (stop) {
      spdlog::warn("stopped before the run was complete ({})", evaluator.Missing());
      return 130;
    }
    msg::GroundTruth t;
    dds::SampleTimes times;
    while (truth_reader.TryTake(&t, nullptr, &times)) evaluator.AddTruth(dds::FromMsg(t), times.written_ns);
    for (auto& [id, reader] : estimate_readers) {
      msg::Estimate e;
      while (reader->TryTake(&e, nullptr, &times)) {
        if (e.stamp().robot_id() != id) {
          spdlog::warn("estimate on {}'s topic claims robot '{}': ignored", id, e.stamp().robot_id());
          continue;
        }
        RobotEstimate estimate = FromEstimateMsg(e);
        estimate.written_ns = times.written_ns;
        estimate.received_ns = times.received_ns;
        evaluator.AddEstimate(id, estimate);
      }
    }
    for (auto& [id, reader] : sensor_readers) {
      msg::SensorStep o;
      while (reader->TryTake(&o, nullptr, &times))
        evaluator.AddOdometry(id, dds::FromMsg(o).odometry, times.written_ns);
    }
    for (auto& [id, reader] : final_readers) {
      msg::FinalTrajectory f;
      while (reader->TryTake(&f)) {
        const std::string problem =
            f.stamp().robot_id() != id ? "it claims robot '" + f.stamp().robot_id() + "'" : FinalChunkProblem(f);
        if (!problem.empty()) {
          spdlog::warn("final trajectory chunk on {}'s topic ignored: {}", id, problem);
          continue;
        }
        evaluator.AddFinalTrajectory(id, f.chunk(), FromFinalMsg(f));
      }
    }
    if (evaluator.Taken() != taken) {
      taken = evaluator.Taken();
      last_new = Clock::now();
    }
    if (Clock::now() - last_new > timeout) {
      throw std::runtime_error(fmt::format(
          "the run is gone: nothing new from world_sim or the agents for {:g} s (twice run.ack_timeout_s); missing {}",
          timeout.count(), evaluator.Missing()));
    }
    // Samples are taken in batches: after a wake-up the loop lets more arrive for kGather
    // before it drains the readers, instead of waking for each one. The delivery figures do
    // not move: a sample's reception time is taken as it arrives (dds::SampleTimes).
    if (notifier.Wait(&seen, std::chrono::milliseconds(100))) std::this_thread::sleep_for(kGather);
  }
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  if (evaluator.TruthStepsLost() > 0) {
    spdlog::warn("{} steps' truth did not come (the evaluator fell behind world_sim's history): scored without them",
                 evaluator.TruthStepsLost());
  }
  const auto summary = evaluator.Finish(wall);
  for (const auto& [id, r] : summary["robots"].items()) {
    spdlog::info("{}: position RMSE {:.3f} m, heading RMSE {:.2f} deg, landmark RMSE {:.3f} m, dead reckoning {:.3f} m",
                 id, r["position_rmse_m"].get<double>(), r["heading_rmse_deg"].get<double>(),
                 r["landmark_rmse_m"].get<double>(), r["dead_reckoning_rmse_m"].get<double>());
  }
  spdlog::info("wrote {}/summary.json, metrics.csv, tracks.csv, view.jsonl, trajectories/", out_dir);
  return 0;
}

}  // namespace
}  // namespace mrslam::evaluator

int main(int argc, char** argv) {
  using namespace mrslam;
  common::CommonFlags flags;
  std::string out_dir;
  const auto add_flags = [&](CLI::App& app) {
    common::AddCommonFlags(app, &flags);
    app.add_option("--out", out_dir, "Output folder")->required();
  };
  mrslam::dds::ExitProcess(
      common::RunMain("evaluator", "mrslam evaluator: scores every robot's estimates against the ground truth", argc,
                      argv, add_flags, [&](const CLI::App&) {
                        common::SetupLogging("evaluator", flags.log_level);
                        const auto scenario = common::LoadScenarioFromFlags(flags);
                        const int domain = mrslam::dds::ResolveDomain(scenario.run.domain, flags.domain);
                        const mrslam::dds::ParticipantOptions dds_options{domain, "evaluator", flags.shared_memory,
                                                                          flags.security_dir, "evaluator"};
                        return evaluator::Evaluate(scenario, dds_options, out_dir, common::InstallStopHandler());
                      }));
}
