#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

// Watching a run's progress from outside, as one more DDS participant in its domain.
namespace mrslam::launch {

// What the monitor has seen so far.
struct Progress {
  int steps_done = 0;                      // the lowest step for which every robot has published its estimate
  int clock_step = 0;                      // the last step the simulator has published
  int rendezvous = 0;                      // encounters reported by the agents (each pair and step counted once)
  std::map<std::string, int> robot_steps;  // robot -> the last step of its estimates
};

// Joins a run's DDS domain, notes which participants join, and reads the simulator's clock and
// every robot's estimate (read only; it is not part of the lockstep barrier). Poll() drains what arrived; the readers'
// threads only queue samples. Owns its participant and readers; they go away with it.
class ProgressMonitor {
 public:
  // Throws mrslam::dds::DdsError when the participant or a reader cannot be created.
  // With a security folder, it joins with the identity "monitor". With serve_discovery_at
  // (HOST:PORT) its participant is the run's discovery server (it then sees every participant).
  ProgressMonitor(int domain, bool shared_memory, const std::string& security_dir,
                  const std::vector<std::string>& robot_ids, const std::string& serve_discovery_at = "");
  ~ProgressMonitor();
  ProgressMonitor(const ProgressMonitor&) = delete;
  ProgressMonitor& operator=(const ProgressMonitor&) = delete;

  // True once a participant with this name (e.g. "evaluator") has joined the domain.
  bool HasSeenParticipant(const std::string& name);

  // Takes every queued sample and returns the progress so far.
  Progress Poll();

  // Forgets how far a robot had come: its agent was restarted and publishes again from step 1.
  void Restarted(const std::string& robot_id) { last_step_[robot_id] = 0; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::map<std::string, int> last_step_;                                 // robot -> last estimate step
  std::map<std::pair<std::string, std::string>, std::set<int>> events_;  // (self, peer) -> steps
  int clock_step_ = 0;
};

// Counts encounters from each robot's reported rendezvous steps per peer: a pair (i, j) counts
// max(#steps i reported about j, #steps j reported about i), so an encounter that both robots
// report counts once.
int CountEncounters(const std::map<std::pair<std::string, std::string>, std::set<int>>& events);

}  // namespace mrslam::launch
