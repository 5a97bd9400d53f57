#include "robot_agent/cooperation/held_factors.h"

#include <filesystem>

#include "common/snapshot_file.h"

namespace mrslam::robot_agent::cooperation {

std::string HeldFactorsPath(const std::string& dir, const std::string& robot) {
  return (std::filesystem::path(dir) / (robot + ".factors")).string();
}

void WriteHeldFactors(const std::string& path, std::uint32_t step, const HeldFactors& held) {
  common::Archive ar = common::Archive::ForWriting();
  HeldFactors copy = held;
  copy.Io(ar);
  common::WriteSnapshot(path, kHeldFactorsRun, {step, ar.bytes()});
}

HeldFactors ReadHeldFactors(const std::string& path) {
  const auto snapshot = common::ReadSnapshot(path, kHeldFactorsRun);
  if (!snapshot) throw common::SnapshotError("held factors " + path + ": no such file");
  common::Archive ar = common::Archive::ForReading(snapshot->payload);
  HeldFactors held;
  held.Io(ar);
  if (!ar.AtEnd()) throw common::ArchiveError("held factors " + path + ": bytes left over");
  return held;
}

}  // namespace mrslam::robot_agent::cooperation
