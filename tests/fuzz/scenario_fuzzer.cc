// libFuzzer harness: any text given as a scenario is parsed and validated or rejected with a
// ScenarioError; nothing else may escape, crash, hang or leak.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/config/scenario_options.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    mrslam::common::ParseScenario(std::string(reinterpret_cast<const char*>(data), size));
  } catch (const mrslam::common::ScenarioError&) {
    // The expected answer to bad input: a one-line reason.
  }
  return 0;
}
