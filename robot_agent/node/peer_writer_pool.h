#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "common/dds/participant.h"
#include "robot_agent/node/peer_endpoints.h"

namespace mrslam::robot_agent {

// The agent's writers toward its peers, opened when first asked for. Opening a writer pairs it
// with every reader the participant has discovered (a 32-robot team: about 4,000 readers, 9-275
// ms per peer on a 2-core VM), which on the agent's own thread delayed the next step's estimate.
// In the background (realtime) a thread of the pool opens them and Get returns nullptr until
// they are open; otherwise (lockstep, whose steps wait for every agent anyway) Get opens them at
// once. Writers stay open until the pool is destroyed (before its participant).
class PeerWriterPool {
 public:
  PeerWriterPool(dds::Participant& participant, std::string self, bool share_factors, bool in_background);
  ~PeerWriterPool();
  PeerWriterPool(const PeerWriterPool&) = delete;
  PeerWriterPool& operator=(const PeerWriterPool&) = delete;

  // The writers toward peer, or nullptr while they are being opened (they are asked for then).
  // Throws dds::DdsError if the thread could not open some.
  PeerWriters* Get(const std::string& peer);
  // Waits until every writer asked for is open, or the deadline; true if they all are.
  bool WaitAllOpen(std::chrono::steady_clock::time_point deadline);
  // The writers opened so far, by peer.
  std::map<std::string, PeerWriters*> Open();

 private:
  void OpenAsked();  // the thread: opens the writers asked for, one peer after another

  dds::Participant& participant_;
  const std::string self_;
  const bool share_factors_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, std::unique_ptr<PeerWriters>> open_;  // guarded by mutex_
  std::deque<std::string> asked_;                             // guarded by mutex_
  std::set<std::string> pending_;                             // asked, not open yet; guarded
  std::string error_;   // why the thread could not open writers (thrown by Get); guarded
  bool stop_ = false;   // guarded by mutex_
  std::thread thread_;  // in the background only
};

}  // namespace mrslam::robot_agent
