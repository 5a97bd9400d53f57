#include "scripts/view/frame_hub.h"

#include <utility>

namespace mrslam::view {

void FrameHub::Publish(std::string frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    frame_ = std::move(frame);
    ++version_;
  }
  cv_.notify_all();
}

bool FrameHub::WaitNewer(std::uint64_t* version, std::string* frame, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!cv_.wait_for(lock, timeout, [&] { return closed_ || version_ != *version; })) return false;
  if (version_ == *version) return false;  // closed
  *version = version_;
  *frame = frame_;
  return true;
}

void FrameHub::Pause(std::chrono::milliseconds duration) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_for(lock, duration, [&] { return closed_; });
}

void FrameHub::Close() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
  }
  cv_.notify_all();
}

bool FrameHub::closed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return closed_;
}

}  // namespace mrslam::view
