#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/sensor_types.h"

namespace mrslam::robot_agent::cooperation {

// Why an agent did not take an incoming sensor sample or peer message (docs/design.md, "Bad
// input"). Malformed, foreign-writer, contested and beyond-horizon rejections fail the run unless
// the user accepts them; stale and duplicate ones are counted apart and never fail it.
enum class Rejection : std::uint8_t {
  kMalformed,      // not a valid value (NaN, a wrong robot, not for this agent, ...)
  kForeignWriter,  // a sensor sample not written by the participant that runs the step clock
  kContested,      // a second participant writing the step clock, or more peer messages than announced
  kBeyondHorizon,  // stamped further ahead than the agent buffers
  kStale,          // of a step already processed
  kDuplicate,      // a second sample of a step from the same writer
};
inline constexpr int kRejectionKinds = 6;
const char* RejectionName(Rejection kind);
bool FailsTheRun(Rejection kind);

struct RejectionCounts {
  std::array<std::uint32_t, kRejectionKinds> by_kind{};

  void Add(Rejection kind, std::uint32_t n = 1) { by_kind[static_cast<int>(kind)] += n; }
  std::uint32_t Of(Rejection kind) const { return by_kind[static_cast<int>(kind)]; }
  std::uint32_t Total() const;
  std::uint32_t Failing() const;
  // "2 foreign-writer, 1 stale" (the kinds with a count, in the enum's order); "none" if none.
  std::string Describe() const;
};

using common::WriterId;

// One sensor stream's samples, buffered by step until the agent processes the step, each with
// the participant that wrote it. The agent takes a step's sample only from the simulator (the
// participant whose writer delivers the step clock); the others of that step are counted as
// foreign-writer when the step is taken. Pure; not thread-safe.
template <typename T>
class StepSlots {
 public:
  explicit StepSlots(std::uint32_t horizon_steps) : horizon_steps_(horizon_steps) {}

  // Buffers the sample of `step` from `writer`, or says why not: stale (a step already
  // processed), beyond the horizon (more than horizon_steps after next_step), duplicate (this
  // writer already sent that step), or foreign-writer (the step already holds a sample from
  // kMaxWriters writers).
  std::optional<Rejection> Offer(std::uint32_t step, std::uint32_t next_step, const WriterId& writer, T sample) {
    if (step < next_step) return Rejection::kStale;
    if (step - next_step > horizon_steps_) return Rejection::kBeyondHorizon;
    auto& slot = slots_[step];
    for (const auto& held : slot) {
      if (held.first == writer) return Rejection::kDuplicate;
    }
    if (slot.size() >= kMaxWriters) return Rejection::kForeignWriter;
    slot.emplace_back(writer, std::move(sample));
    return std::nullopt;
  }
  bool Has(std::uint32_t step, const WriterId& simulator) const {
    const auto it = slots_.find(step);
    if (it == slots_.end()) return false;
    for (const auto& held : it->second) {
      if (held.first == simulator) return true;
    }
    return false;
  }
  // The simulator's sample of `step` (Has must be true); the others of that step are counted.
  T Take(std::uint32_t step, const WriterId& simulator, RejectionCounts* counts) {
    auto node = slots_.extract(step);
    T out{};
    for (auto& [writer, sample] : node.mapped()) {
      if (writer == simulator) {
        out = std::move(sample);
      } else {
        counts->Add(Rejection::kForeignWriter);
      }
    }
    return out;
  }

 private:
  static constexpr std::size_t kMaxWriters = 4;
  std::uint32_t horizon_steps_;
  std::map<std::uint32_t, std::vector<std::pair<WriterId, T>>> slots_;
};

// Which participant is the simulator: the first to deliver the step clock. A clock from
// another participant is contested (without DDS-Security nothing proves which is genuine, so
// the run must not pass silently).
class SimulatorBinding {
 public:
  std::optional<Rejection> OfferClock(const WriterId& writer) {
    if (!simulator_) simulator_ = writer;
    if (*simulator_ != writer) return Rejection::kContested;
    return std::nullopt;
  }
  const std::optional<WriterId>& simulator() const { return simulator_; }

 private:
  std::optional<WriterId> simulator_;
};

}  // namespace mrslam::robot_agent::cooperation
