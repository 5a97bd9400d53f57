#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/se2.h"

// Reading the UTIAS MRCLAM data set (Leung et al., IJRR 2011): whitespace-separated text
// tables with '#' header lines. The reader tolerates CRLF endings, trailing blanks, blank and
// comment lines and several rows per time stamp; a malformed row is reported ("file:line:
// reason") and skipped; a missing or unreadable file throws MrclamError with a one-line reason.
namespace mrslam::world_sim {

// A data folder or file that cannot be read at all.
class MrclamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One table file: rows of exactly `columns` finite numbers. Malformed rows are appended to
// `problems` as "path:line: reason" and skipped.
struct MrclamTable {
  std::vector<std::vector<double>> rows;
  std::vector<std::string> problems;
};
MrclamTable ReadMrclamTable(const std::string& path, std::size_t columns);

struct MrclamPose {
  double time_s = 0.0;  // Unix time, as recorded
  common::Pose2 pose;   // global (Vicon) frame
};

struct MrclamCommand {
  double time_s = 0.0;  // Unix time; the command holds until the next one
  double v_mps = 0.0;
  double w_radps = 0.0;
};

struct MrclamMeasurement {
  double time_s = 0.0;  // Unix time
  int barcode = 0;      // barcode, not subject (despite the files' header)
  double range_m = 0.0;
  double bearing_rad = 0.0;
};

struct MrclamLandmark {
  int subject = 0;
  double x_m = 0.0;
  double y_m = 0.0;
  double sd_x_m = 0.0;
  double sd_y_m = 0.0;
};

// One robot's three files, each sorted by time (stable: rows of one time stamp keep their order).
struct MrclamRobot {
  int subject = 0;
  std::vector<MrclamPose> groundtruth;
  std::vector<MrclamCommand> odometry;
  std::vector<MrclamMeasurement> measurements;
};

// The parts of a data set folder that a replay needs.
struct MrclamDataset {
  std::map<int, int> subject_of_barcode;  // Barcodes.dat
  std::vector<MrclamLandmark> landmarks;  // Landmark_Groundtruth.dat
  std::map<int, MrclamRobot> robots;      // by subject
  // Every malformed row of every file read, "path:line: reason".
  std::vector<std::string> problems;
  // The earliest ground-truth time stamp of the robots read: time 0 of the replay.
  double start_time_s = 0.0;
};

// Reads Barcodes.dat, Landmark_Groundtruth.dat and, for every subject in `robot_subjects`,
// RobotN_Groundtruth.dat, RobotN_Odometry.dat and RobotN_Measurement.dat from `dir`.
// Throws MrclamError when a file is missing or a robot has no ground truth.
MrclamDataset ReadMrclamDataset(const std::string& dir, const std::vector<int>& robot_subjects);

// The robot's ground-truth pose at `time_s` (Unix): linear in position, shortest-arc in
// heading between the two nearest records; held constant before the first and after the last.
common::Pose2 InterpolatePose(const std::vector<MrclamPose>& groundtruth, double time_s);

}  // namespace mrslam::world_sim
