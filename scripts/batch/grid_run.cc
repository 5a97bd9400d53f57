#include "scripts/batch/grid_run.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/config/agent_options_projection.h"
#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/node/msg_conversion.h"
#include "scripts/launch/domain_picker.h"
#include "scripts/launch/process_supervisor.h"
#include "scripts/launch/simulation_run.h"
#include "world_sim/core/world.h"
#include "world_sim/evaluator/paper_b_scorer.h"

namespace mrslam::batch {
namespace {

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

}  // namespace

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
    filters.push_back(robot_agent::factory::CreateFilter(common::AgentOptionsFor(options, robot.id), options.seed));
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

}  // namespace mrslam::batch
