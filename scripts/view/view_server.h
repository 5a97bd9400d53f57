#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "scripts/view/frame_hub.h"

// The viewer's HTTP side.
namespace mrslam::view {

// What the server serves besides the page: /info (the mode and the run's header, JSON), and
// either /events (live: the hub's frames as Server-Sent Events) or /steps (replay: every step).
struct ViewContent {
  std::string info_json;
  FrameHub* hub = nullptr;  // live
  std::string steps_json;   // replay
};

// Serves the page (embedded in the binary), its script and the content on 127.0.0.1 only, from
// a listening thread of its own; each live client is paced to at most one frame per
// min_frame_period and skips the frames it is too slow for. Owns the server and its thread.
class ViewServer {
 public:
  ViewServer(ViewContent content, std::chrono::milliseconds min_frame_period);
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  // Binds 127.0.0.1:port (0: a free port) and starts serving. Returns the port; throws
  // std::runtime_error when it cannot bind.
  int Start(int port);
  // Stops serving (the hub must be closed first, or live clients hold their threads).
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mrslam::view
