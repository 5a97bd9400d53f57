#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>

#include "common/config/scenario_options.h"
#include "common/dds/participant.h"
#include "scripts/view/frame_hub.h"

// The live side of the viewer: one more reader in a run's DDS domain.
namespace mrslam::view {

// Reads a run as it goes (the step clock, the truth, every robot's estimate and lidar scan) and
// publishes the view's frame of the latest state (evaluator::ViewStep) to the hub, at most once
// per period and only when something changed. The DDS listener threads only queue samples; a
// thread of its own drains them and builds the frames, so the run never waits for the viewer or
// its clients. Owns its participant, readers and thread.
class LiveFeed {
 public:
  // Throws mrslam::dds::DdsError when the participant or a reader cannot be created.
  LiveFeed(const common::ScenarioOptions& scenario, const dds::ParticipantOptions& participant, FrameHub* hub,
           std::chrono::milliseconds period);
  ~LiveFeed();
  LiveFeed(const LiveFeed&) = delete;
  LiveFeed& operator=(const LiveFeed&) = delete;

  // Stops the thread, then publishes what arrived since its last frame (the run's end).
  void Stop();

 private:
  struct State;
  void Loop(std::chrono::milliseconds period);

  std::unique_ptr<State> state_;
  FrameHub* hub_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace mrslam::view
