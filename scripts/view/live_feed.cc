#include "scripts/view/live_feed.h"

#include <map>
#include <optional>
#include <string>

#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "world_sim/evaluator/estimate_msg.h"
#include "world_sim/evaluator/view_steps.h"

namespace mrslam::view {

// The readers and the latest state they delivered (touched by the feed's thread only).
struct LiveFeed::State {
  dds::Participant participant;
  dds::Reader<msg::StepClockPubSubType> clock;
  dds::Reader<msg::GroundTruthPubSubType> truth;
  std::map<std::string, std::unique_ptr<dds::Reader<msg::EstimatePubSubType>>> estimate_readers;
  std::map<std::string, std::unique_ptr<dds::Reader<msg::SensorStepPubSubType>>> sensor_readers;

  std::uint32_t step = 0;
  double time_s = 0.0;
  std::optional<common::GroundTruth> latest_truth;
  std::map<std::string, evaluator::RobotEstimate> estimates;
  std::map<std::string, common::LidarScan> scans;

  State(const common::ScenarioOptions& scenario, const dds::ParticipantOptions& options)
      : participant(options), clock(participant, dds::kClockTopic), truth(participant, dds::kTruthTopic) {
    for (const auto& r : scenario.robots) {
      estimate_readers[r.id] =
          std::make_unique<dds::Reader<msg::EstimatePubSubType>>(participant, dds::EstimateTopic(r.id));
      sensor_readers[r.id] =
          std::make_unique<dds::Reader<msg::SensorStepPubSubType>>(participant, dds::SensorTopic(r.id));
    }
  }
  ~State() {  // readers before their participant
    estimate_readers.clear();
    sensor_readers.clear();
  }

  // Takes every queued sample into the latest state; true when anything arrived.
  bool Drain() {
    bool changed = false;
    msg::StepClock c;
    while (clock.TryTake(&c)) {
      changed = true;
      if (c.stamp().step() < step) continue;
      step = c.stamp().step();
      time_s = c.stamp().time_s();
    }
    msg::GroundTruth t;
    while (truth.TryTake(&t)) {
      changed = true;
      if (!latest_truth || t.stamp().step() >= latest_truth->stamp.step) latest_truth = dds::FromMsg(t);
    }
    for (auto& [id, reader] : estimate_readers) changed = DrainEstimates(id, *reader) || changed;
    for (auto& [id, reader] : sensor_readers) changed = DrainScans(id, *reader) || changed;
    return changed;
  }

  bool DrainEstimates(const std::string& id, dds::Reader<msg::EstimatePubSubType>& reader) {
    msg::Estimate e;
    bool any = false;
    while (reader.TryTake(&e)) {
      any = true;
      if (e.stamp().robot_id() == id) estimates[id] = evaluator::FromEstimateMsg(e);
    }
    return any;
  }

  bool DrainScans(const std::string& id, dds::Reader<msg::SensorStepPubSubType>& reader) {
    msg::SensorStep s;
    bool any = false;
    while (reader.TryTake(&s)) {
      any = true;
      scans[id] = dds::FromMsg(s).lidar;
    }
    return any;
  }

  std::string Frame() const {
    evaluator::ViewStepInput input;
    input.step = step;
    input.time_s = time_s;
    input.truth = latest_truth ? &*latest_truth : nullptr;
    for (const auto& [id, e] : estimates) input.estimates[id] = &e;
    for (const auto& [id, s] : scans) input.scans[id] = &s;
    return evaluator::ViewStep(input).dump();
  }
};

LiveFeed::LiveFeed(const common::ScenarioOptions& scenario, const dds::ParticipantOptions& participant, FrameHub* hub,
                   std::chrono::milliseconds period)
    : state_(std::make_unique<State>(scenario, participant)), hub_(hub) {
  thread_ = std::thread([this, period] { Loop(period); });
}

LiveFeed::~LiveFeed() { Stop(); }

void LiveFeed::Stop() {
  if (!thread_.joinable()) return;
  stop_ = true;
  thread_.join();
  if (state_->Drain()) hub_->Publish(state_->Frame());
}

void LiveFeed::Loop(std::chrono::milliseconds period) {
  while (!stop_) {
    if (state_->Drain()) hub_->Publish(state_->Frame());
    std::this_thread::sleep_for(period);
  }
}

}  // namespace mrslam::view
