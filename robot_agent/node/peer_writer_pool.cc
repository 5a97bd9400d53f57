#include "robot_agent/node/peer_writer_pool.h"

#include <exception>
#include <utility>

namespace mrslam::robot_agent {

PeerWriterPool::PeerWriterPool(dds::Participant& participant, std::string self, bool share_factors, bool in_background)
    : participant_(participant), self_(std::move(self)), share_factors_(share_factors) {
  if (in_background) thread_ = std::thread([this] { OpenAsked(); });
}

PeerWriterPool::~PeerWriterPool() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

PeerWriters* PeerWriterPool::Get(const std::string& peer) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!error_.empty()) throw dds::DdsError(error_);
  if (const auto it = open_.find(peer); it != open_.end()) return it->second.get();
  if (!thread_.joinable()) {
    lock.unlock();
    auto writers = std::make_unique<PeerWriters>(participant_, self_, peer, share_factors_);
    lock.lock();
    return (open_[peer] = std::move(writers)).get();
  }
  if (pending_.insert(peer).second) {
    asked_.push_back(peer);
    changed_.notify_all();
  }
  return nullptr;
}

bool PeerWriterPool::WaitAllOpen(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  return changed_.wait_until(lock, deadline, [this] { return pending_.empty(); });
}

std::map<std::string, PeerWriters*> PeerWriterPool::Open() {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::map<std::string, PeerWriters*> out;
  for (const auto& [peer, writers] : open_) out[peer] = writers.get();
  return out;
}

void PeerWriterPool::OpenAsked() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    changed_.wait(lock, [this] { return stop_ || !asked_.empty(); });
    if (stop_) return;
    const std::string peer = asked_.front();
    asked_.pop_front();
    lock.unlock();
    std::unique_ptr<PeerWriters> writers;
    std::string error;
    try {
      writers = std::make_unique<PeerWriters>(participant_, self_, peer, share_factors_);
    } catch (const std::exception& e) {
      error = e.what();
    }
    lock.lock();
    if (writers) open_[peer] = std::move(writers);
    if (!error.empty()) error_ = error;
    pending_.erase(peer);
    changed_.notify_all();
  }
}

}  // namespace mrslam::robot_agent
