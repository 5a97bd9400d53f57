#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>

// The latest frame of the live view, handed from the one thread that builds frames to any
// number of clients (Server-Sent Events). Holds one frame only: publishing replaces it, and a
// client that is slower than the frames simply skips some; nothing ever waits for a client.
namespace mrslam::view {

class FrameHub {
 public:
  // Replaces the latest frame and wakes the waiting clients.
  void Publish(std::string frame);

  // Waits up to timeout for a frame newer than *version (0: none yet). True with the frame and
  // its version when one is there (also once closed: the last frame is still handed out);
  // false on timeout, or when closed and nothing newer is left.
  bool WaitNewer(std::uint64_t* version, std::string* frame, std::chrono::milliseconds timeout);

  // Waits for the given time unless the hub is closed first.
  void Pause(std::chrono::milliseconds duration);

  // Wakes every waiting client for good (the viewer is stopping).
  void Close();
  bool closed() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::string frame_;
  std::uint64_t version_ = 0;
  bool closed_ = false;
};

}  // namespace mrslam::view
