#include "robot_agent/cooperation/sample_intake.h"

namespace mrslam::robot_agent::cooperation {

const char* RejectionName(Rejection kind) {
  static constexpr std::array<const char*, kRejectionKinds> kNames = {"malformed",      "foreign-writer", "contested",
                                                                      "beyond-horizon", "stale",          "duplicate"};
  return kNames[static_cast<int>(kind)];
}

bool FailsTheRun(Rejection kind) { return kind != Rejection::kStale && kind != Rejection::kDuplicate; }

std::uint32_t RejectionCounts::Total() const {
  std::uint32_t n = 0;
  for (const std::uint32_t c : by_kind) n += c;
  return n;
}

std::uint32_t RejectionCounts::Failing() const {
  std::uint32_t n = 0;
  for (int k = 0; k < kRejectionKinds; ++k) {
    if (FailsTheRun(static_cast<Rejection>(k))) n += by_kind[k];
  }
  return n;
}

std::string RejectionCounts::Describe() const {
  std::string out;
  for (int k = 0; k < kRejectionKinds; ++k) {
    if (by_kind[k] == 0) continue;
    if (!out.empty()) out += ", ";
    out += std::to_string(by_kind[k]) + " " + RejectionName(static_cast<Rejection>(k));
  }
  return out.empty() ? "none" : out;
}

}  // namespace mrslam::robot_agent::cooperation
