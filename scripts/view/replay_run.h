#pragma once

#include <string>

// The replay side of the viewer: a finished run's folder.
namespace mrslam::view {

// A finished run as the page replays it: the header and every step of DIR/view.jsonl.
struct ReplayRun {
  std::string header_json;  // the first line
  std::string steps_json;   // a JSON array of the steps, in file order
  int steps = 0;
};

// Reads DIR/view.jsonl (written by the evaluator). Throws std::runtime_error naming the file
// (and the line) when it is missing, empty or not JSON Lines.
ReplayRun LoadReplayRun(const std::string& dir);

}  // namespace mrslam::view
