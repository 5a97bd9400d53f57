// libFuzzer harness: any bytes a writer could put on an agent's sensor topic or the step clock
// (the first byte picks the message type, even a sensor step, odd a clock; the rest is its CDR
// payload) go through the agent's intake — decoding, conversion, stamp check, sanitizing,
// buffering by step — without a crash, a hang or a leak.
#include <cstddef>
#include <cstdint>

#include "common/dds/msg_conversion.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/cooperation/sample_intake.h"
#include "robot_agent/cooperation/sample_validation.h"
#include "tests/fuzz/cdr_input.h"

namespace mrslam::fuzz {
namespace {

constexpr std::uint32_t kNextStep = 5;
constexpr std::uint32_t kHorizon = 1000;
const common::WriterId kWriter{1, 2, 3};

void Intake(const std::uint8_t* data, std::size_t size) {
  msg::SensorStep message;
  if (!Decode<msg::SensorStepPubSubType>(data, size, &message)) return;
  common::SensorStep sample = dds::FromMsg(message);
  const std::uint32_t step = sample.odometry.stamp.step;
  if (!robot_agent::cooperation::StampProblem(sample.odometry.stamp, "r1").empty()) return;
  robot_agent::cooperation::SanitizeSensorStep(&sample);
  robot_agent::cooperation::StepSlots<common::SensorStep> slots(kHorizon);
  if (slots.Offer(step, kNextStep, kWriter, std::move(sample))) return;
  robot_agent::cooperation::RejectionCounts counts;
  if (slots.Has(step, kWriter)) slots.Take(step, kWriter, &counts);
}

}  // namespace
}  // namespace mrslam::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mrslam;
  if (size == 0) return 0;
  const std::uint8_t* payload = data + 1;
  const std::size_t n = size - 1;
  if (data[0] % 2 == 0) {
    fuzz::Intake(payload, n);
  } else {
    msg::StepClock clock;
    if (fuzz::Decode<msg::StepClockPubSubType>(payload, n, &clock)) dds::FromMsg(clock.stamp());
  }
  return 0;
}
