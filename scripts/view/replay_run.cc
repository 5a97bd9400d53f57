#include "scripts/view/replay_run.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace mrslam::view {

namespace {

nlohmann::json ParseLine(const std::string& line, const std::string& path, int number) {
  try {
    return nlohmann::json::parse(line);
  } catch (const nlohmann::json::exception&) {
    throw std::runtime_error(path + " line " + std::to_string(number) + " is not JSON");
  }
}

}  // namespace

ReplayRun LoadReplayRun(const std::string& dir) {
  const std::string path = dir + "/view.jsonl";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path + " (the evaluator writes it into a run's folder)");
  ReplayRun run;
  std::string line;
  int number = 0;
  run.steps_json = "[";
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    const auto value = ParseLine(line, path, number);
    if (!value.is_object()) throw std::runtime_error(path + " line " + std::to_string(number) + " is not an object");
    if (number == 1) {
      if (!value.contains("robots")) throw std::runtime_error(path + " has no header line");
      run.header_json = line;
      continue;
    }
    run.steps_json += (run.steps == 0 ? "" : ",") + line;
    ++run.steps;
  }
  run.steps_json += "]";
  if (run.header_json.empty()) throw std::runtime_error(path + " is empty");
  if (run.steps == 0) throw std::runtime_error(path + " holds no step");
  return run;
}

}  // namespace mrslam::view
