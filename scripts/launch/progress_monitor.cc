#include "scripts/launch/progress_monitor.h"

#include <algorithm>
#include <climits>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>

#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"

namespace mrslam::launch {

// Records the names of the participants that join the domain (called on a DDS thread).
class DiscoveryListener : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant* /*participant*/,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) return;
    std::lock_guard<std::mutex> lock(mutex_);
    names_.insert(info.info.m_participantName.to_string());
  }
  bool Seen(const std::string& name) {
    std::lock_guard<std::mutex> lock(mutex_);
    return names_.count(name) > 0;
  }

 private:
  std::mutex mutex_;
  std::set<std::string> names_;
};

struct ProgressMonitor::Impl {
  DiscoveryListener discovery;
  dds::Participant participant;
  dds::Reader<msg::StepClockPubSubType> clock;
  std::map<std::string, std::unique_ptr<dds::Reader<msg::EstimatePubSubType>>> estimates;

  Impl(int domain, bool shared_memory, const std::string& security_dir, const std::vector<std::string>& robot_ids,
       const std::string& serve_discovery_at)
      : participant({domain, "mrslam_launch", shared_memory, security_dir, "monitor", 0, serve_discovery_at}),
        clock(participant, dds::kClockTopic) {
    participant.get()->set_listener(&discovery, eprosima::fastdds::dds::StatusMask::none());
    for (const auto& id : robot_ids) {
      estimates[id] = std::make_unique<dds::Reader<msg::EstimatePubSubType>>(participant, dds::EstimateTopic(id));
    }
  }
  ~Impl() {
    participant.get()->set_listener(nullptr);
    estimates.clear();  // readers before their participant
  }
};

ProgressMonitor::ProgressMonitor(int domain, bool shared_memory, const std::string& security_dir,
                                 const std::vector<std::string>& robot_ids, const std::string& serve_discovery_at)
    : impl_(std::make_unique<Impl>(domain, shared_memory, security_dir, robot_ids, serve_discovery_at)) {
  for (const auto& id : robot_ids) last_step_[id] = 0;
}

ProgressMonitor::~ProgressMonitor() = default;

bool ProgressMonitor::HasSeenParticipant(const std::string& name) { return impl_->discovery.Seen(name); }

Progress ProgressMonitor::Poll() {
  msg::StepClock clock;
  while (impl_->clock.TryTake(&clock)) {
    clock_step_ = std::max(clock_step_, static_cast<int>(clock.stamp().step()));
  }
  msg::Estimate estimate;
  for (auto& [id, reader] : impl_->estimates) {
    while (reader->TryTake(&estimate)) {
      last_step_[id] = std::max(last_step_[id], static_cast<int>(estimate.stamp().step()));
      for (const auto& event : estimate.rendezvous()) {
        events_[{id, event.peer_id()}].insert(static_cast<int>(event.step()));
      }
    }
  }
  Progress p;
  p.clock_step = clock_step_;
  int lowest = INT_MAX;
  for (const auto& entry : last_step_) lowest = std::min(lowest, entry.second);
  p.steps_done = last_step_.empty() ? clock_step_ : lowest;
  p.rendezvous = CountEncounters(events_);
  p.robot_steps = last_step_;
  return p;
}

int CountEncounters(const std::map<std::pair<std::string, std::string>, std::set<int>>& events) {
  int total = 0;
  for (const auto& [pair, steps] : events) {
    const auto& [self, peer] = pair;
    const auto reverse = events.find({peer, self});
    const int other = reverse == events.end() ? 0 : static_cast<int>(reverse->second.size());
    const int mine = static_cast<int>(steps.size());
    if (mine > other || (mine == other && self < peer)) total += mine;
  }
  return total;
}

}  // namespace mrslam::launch
