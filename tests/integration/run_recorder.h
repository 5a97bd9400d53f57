#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "mrslamPubSubTypes.h"
#include "tests/integration/child_process.h"

namespace mrslam::testing {

// Runs world_sim and one robot_agent per robot and records the run as the evaluator would: the
// ground truth by step and every robot's estimates.
class RunRecorder {
 public:
  RunRecorder(int domain, const common::ScenarioOptions& scenario)
      : participant_({domain, "run_recorder", false}), truth_reader_(participant_, dds::kTruthTopic) {
    for (const auto& r : scenario.robots) {
      readers_[r.id] = std::make_unique<dds::Reader<msg::EstimatePubSubType>>(participant_, dds::EstimateTopic(r.id));
      robot_ids_.push_back(r.id);
    }
  }

  // Starts one robot_agent per robot of the scenario and world_sim (waiting for this reader of
  // the truth), all with `args`, logs in `dir`; records until world_sim exits, then what is
  // still in flight. Every process must exit 0 in time.
  void Run(const std::vector<std::string>& args, const std::string& dir) {
    const auto agents = StartAgents(robot_ids_, args, dir);
    auto sim_args = args;
    sim_args.insert(sim_args.end(), {"--wait-readers", "1"});
    const auto sim = StartBin("world_sim", sim_args, dir + "/world_sim.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (sim->running() && std::chrono::steady_clock::now() < deadline) {
      Drain(std::chrono::milliseconds(20));
      sim->WaitExit(std::chrono::milliseconds(1));
    }
    ASSERT_EQ(sim->WaitExit(std::chrono::milliseconds(1)), std::optional<int>(0)) << ReadFile(dir + "/world_sim.log");
    for (std::size_t i = 0; i < agents.size(); ++i) {
      const std::string log = dir + "/" + robot_ids_[i] + ".log";
      EXPECT_EQ(agents[i]->WaitExit(std::chrono::seconds(30)), std::optional<int>(0)) << ReadFile(log);
    }
    while (Drain(std::chrono::milliseconds(300))) {
    }
  }

  const std::map<std::uint32_t, common::GroundTruth>& truth() const { return truth_; }
  const std::vector<msg::Estimate>& estimates(const std::string& robot_id) { return estimates_[robot_id]; }

  // The pose of G_robot in the world frame (from the truth of the first step).
  common::Pose2 Frame(const std::string& robot_id) const {
    for (const auto& [id, frame] : truth_.begin()->second.frames) {
      if (id == robot_id) return frame;
    }
    ADD_FAILURE() << "no frame for " << robot_id;
    return {};
  }
  // The robot's true pose at a step, in the world frame.
  common::Pose2 TruePose(std::uint32_t step, const std::string& robot_id) const {
    const auto it = truth_.find(step);
    if (it == truth_.end()) {
      ADD_FAILURE() << "no truth for step " << step;
      return {};
    }
    for (const auto& t : it->second.robots) {
      if (t.id == robot_id) return t.pose;
    }
    ADD_FAILURE() << "no truth for " << robot_id << " at step " << step;
    return {};
  }

 private:
  bool Drain(std::chrono::milliseconds wait) {
    bool any = false;
    msg::GroundTruth t;
    while (truth_reader_.Take(&t, wait)) {
      truth_[t.stamp().step()] = dds::FromMsg(t);
      any = true;
    }
    for (auto& [id, reader] : readers_) {
      msg::Estimate e;
      while (reader->Take(&e, std::chrono::milliseconds(1))) {
        estimates_[id].push_back(e);
        any = true;
      }
    }
    return any;
  }

  dds::Participant participant_;
  dds::Reader<msg::GroundTruthPubSubType> truth_reader_;
  std::map<std::string, std::unique_ptr<dds::Reader<msg::EstimatePubSubType>>> readers_;
  std::vector<std::string> robot_ids_;  // scenario order
  std::map<std::uint32_t, common::GroundTruth> truth_;
  std::map<std::string, std::vector<msg::Estimate>> estimates_;
};

}  // namespace mrslam::testing
