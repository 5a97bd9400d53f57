#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/sensor_types.h"
#include "world_sim/core/step_source.h"
#include "world_sim/replay/mrclam_reader.h"

namespace mrslam::world_sim {

// Counts of what a replay dropped, for the log and the tests.
struct MrclamReplayStats {
  int unknown_barcodes = 0;     // measurements of a barcode not in Barcodes.dat
  int robots_not_replayed = 0;  // measurements of a robot outside the replayed subset
  int measurements = 0;         // measurements published
};

// Replays a UTIAS MRCLAM data set as a StepSource: step k covers the window's interval
// [start_s + (k-1)*step_s, start_s + k*step_s) (seconds after the data set's first ground-truth
// time stamp). Per robot, in scenario order:
// - odometry: the velocity commands holding in that interval, one segment per command (its own
//   start and duration; zero velocity before the first and after the last command);
// - lidar: every measurement in the interval with its own time stamp; landmark barcodes become
//   landmark ids (MRCLAM subject numbers), robot barcodes robot detections of "r<n>";
//   unknown barcodes and robots outside the replay are dropped and counted;
// - IMU: no readings.
// Truth: every robot's ground truth interpolated at the step's end time, the static landmarks
// (ids = subjects) and each robot's frame G_i, placed so that the robot's pose in G_i at the
// window start is the scenario's (default: G_i is the robot's first pose of the window).
// Owns the parsed data. Pure: no DDS, no wall clock.
class MrclamReplay : public StepSource {
 public:
  // Reads options.replay.dir; throws MrclamError when a file is missing. Malformed rows are
  // skipped and listed in problems().
  explicit MrclamReplay(const common::ScenarioOptions& options);

  std::vector<common::SensorStep> Step() override;
  common::GroundTruth Truth() const override;
  std::uint32_t step() const override { return step_; }
  double time_s() const override;

  const MrclamReplayStats& stats() const { return stats_; }
  const std::vector<std::string>& problems() const { return data_.problems; }
  const MrclamDataset& data() const { return data_; }

 private:
  struct ReplayRobot {
    std::string id;
    int subject = 0;
    common::Pose2 frame_in_world;      // G_i in the Vicon frame
    std::size_t next_command = 0;      // first command not yet wholly in the past
    std::size_t next_measurement = 0;  // first measurement not yet published
  };

  // Unix time of the end of step k.
  double UnixTime(std::uint32_t k) const;
  common::Odometry Commands(const MrclamRobot& data, ReplayRobot* robot, double from, double to) const;

  common::ScenarioOptions options_;
  MrclamDataset data_;
  std::vector<ReplayRobot> robots_;  // scenario order
  std::uint32_t step_ = 0;
  MrclamReplayStats stats_;
};

// The MRCLAM subject number of a robot id "r<n>", or -1.
int MrclamSubject(const std::string& robot_id);

}  // namespace mrslam::world_sim
