// libFuzzer harness: any bytes a writer could put on an agent's sensor topics or the step clock
// (the first byte picks the message type, the rest is its CDR payload) go through the agent's
// intake — decoding, conversion, stamp check, sanitizing, buffering by step — without a crash,
// a hang or a leak.
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

template <typename PubSubType, typename Sample>
void Intake(const std::uint8_t* data, std::size_t size, int (*sanitize)(Sample*)) {
  typename PubSubType::type message;
  if (!Decode<PubSubType>(data, size, &message)) return;
  Sample sample = dds::FromMsg(message);
  if (!robot_agent::cooperation::StampProblem(sample.stamp, "r1").empty()) return;
  sanitize(&sample);
  robot_agent::cooperation::StepSlots<Sample> slots(kHorizon);
  const std::uint32_t step = sample.stamp.step;
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
  switch (data[0] % 4) {
    case 0:
      fuzz::Intake<msg::LidarScanPubSubType>(payload, n, &robot_agent::cooperation::SanitizeLidar);
      break;
    case 1:
      fuzz::Intake<msg::ImuPubSubType>(payload, n, &robot_agent::cooperation::SanitizeImu);
      break;
    case 2:
      fuzz::Intake<msg::OdometryPubSubType>(payload, n, &robot_agent::cooperation::SanitizeOdometry);
      break;
    default: {
      msg::StepClock clock;
      if (fuzz::Decode<msg::StepClockPubSubType>(payload, n, &clock)) dds::FromMsg(clock.stamp());
      break;
    }
  }
  return 0;
}
