#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "common/archive.h"
#include "robot_agent/cooperation/factor_exchange.h"

// What an agent holds of the raw measurements at the end of a run (robot_agent --factors-out):
// every origin's steps, the own included, and the bytes of peer messages it sent to and took in
// from each peer. Written as a snapshot file (common/snapshot_file.h) of the run's last step.
namespace mrslam::robot_agent::cooperation {

struct HeldFactors {
  std::string robot;
  std::map<std::string, FactorLog> logs;
  std::map<std::string, std::uint64_t> bytes_sent_to, bytes_received_from;

  void Io(common::Archive& ar) { ar(robot, logs, bytes_sent_to, bytes_received_from); }
};

// The file's name in a folder, and what its snapshot header names as its run.
std::string HeldFactorsPath(const std::string& dir, const std::string& robot);
inline constexpr const char* kHeldFactorsRun = "held factors";

// Writes them atomically after `step`; SnapshotError when the file system refuses.
void WriteHeldFactors(const std::string& path, std::uint32_t step, const HeldFactors& held);
// Reads them back; SnapshotError (missing, cut, of another build) or ArchiveError in one line.
HeldFactors ReadHeldFactors(const std::string& path);

}  // namespace mrslam::robot_agent::cooperation
