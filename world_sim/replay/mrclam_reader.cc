#include "world_sim/replay/mrclam_reader.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>
#include <utility>

#include "common/angles.h"

namespace mrslam::world_sim {

namespace {

// Parses the numbers of one line (blank-separated); false with a reason when the line does not
// hold exactly `columns` finite numbers.
bool ParseRow(const std::string& line, std::size_t columns, std::vector<double>* row, std::string* reason) {
  row->clear();
  const char* p = line.c_str();
  while (true) {
    while (*p == ' ' || *p == '\t') ++p;
    if (*p == '\0') break;
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(p, &end);
    if (end == p || (*end != '\0' && *end != ' ' && *end != '\t')) {
      const char* token_end = p;
      while (*token_end != '\0' && *token_end != ' ' && *token_end != '\t') ++token_end;
      *reason = "'" + std::string(p, token_end) + "' is not a number";
      return false;
    }
    if (errno == ERANGE || !std::isfinite(value)) {
      *reason = "value out of range";
      return false;
    }
    row->push_back(value);
    p = end;
  }
  if (row->size() != columns) {
    *reason = "expected " + std::to_string(columns) + " numbers, got " + std::to_string(row->size());
    return false;
  }
  return true;
}

bool IsInteger(double v) { return std::abs(v) < 1e9 && v == std::floor(v); }

std::string Join(const std::string& dir, const std::string& name) {
  if (dir.empty() || dir.back() == '/') return dir + name;
  return dir + "/" + name;
}

}  // namespace

MrclamTable ReadMrclamTable(const std::string& path, std::size_t columns) {
  std::ifstream in(path);
  if (!in) throw MrclamError("cannot open MRCLAM file '" + path + "'");
  MrclamTable table;
  std::string line;
  std::vector<double> row;
  std::string reason;
  for (int number = 1; std::getline(in, line); ++number) {
    // CRLF endings and trailing blanks.
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;  // blank, header or comment
    if (ParseRow(line, columns, &row, &reason)) {
      table.rows.push_back(row);
    } else {
      std::string problem = path;
      problem.append(":").append(std::to_string(number)).append(": ").append(reason);
      table.problems.push_back(std::move(problem));
    }
  }
  return table;
}

MrclamDataset ReadMrclamDataset(const std::string& dir, const std::vector<int>& robot_subjects) {
  MrclamDataset data;
  const auto keep = [&data](MrclamTable&& t) {
    data.problems.insert(data.problems.end(), t.problems.begin(), t.problems.end());
    return std::move(t.rows);
  };
  const auto reject = [&data](const std::string& path, std::size_t index, const std::string& reason) {
    data.problems.push_back(path + ": row " + std::to_string(index + 1) + ": " + reason);
  };

  const std::string barcodes_path = Join(dir, "Barcodes.dat");
  const auto barcodes = keep(ReadMrclamTable(barcodes_path, 2));
  for (std::size_t i = 0; i < barcodes.size(); ++i) {
    const auto& r = barcodes[i];
    if (!IsInteger(r[0]) || !IsInteger(r[1])) {
      reject(barcodes_path, i, "subject and barcode must be integers");
      continue;
    }
    data.subject_of_barcode[static_cast<int>(r[1])] = static_cast<int>(r[0]);
  }

  const std::string landmarks_path = Join(dir, "Landmark_Groundtruth.dat");
  const auto landmarks = keep(ReadMrclamTable(landmarks_path, 5));
  for (std::size_t i = 0; i < landmarks.size(); ++i) {
    const auto& r = landmarks[i];
    if (!IsInteger(r[0])) {
      reject(landmarks_path, i, "subject must be an integer");
      continue;
    }
    data.landmarks.push_back({static_cast<int>(r[0]), r[1], r[2], r[3], r[4]});
  }

  data.start_time_s = std::numeric_limits<double>::infinity();
  for (const int subject : robot_subjects) {
    const std::string prefix = Join(dir, "Robot" + std::to_string(subject) + "_");
    MrclamRobot robot;
    robot.subject = subject;
    for (const auto& r : keep(ReadMrclamTable(prefix + "Groundtruth.dat", 4))) {
      robot.groundtruth.push_back({r[0], {r[1], r[2], common::WrapAngle(r[3])}});
    }
    for (const auto& r : keep(ReadMrclamTable(prefix + "Odometry.dat", 3))) {
      robot.odometry.push_back({r[0], r[1], r[2]});
    }
    const std::string measurements_path = prefix + "Measurement.dat";
    const auto measurements = keep(ReadMrclamTable(measurements_path, 4));
    for (std::size_t i = 0; i < measurements.size(); ++i) {
      const auto& r = measurements[i];
      if (!IsInteger(r[1])) {
        reject(measurements_path, i, "barcode must be an integer");
        continue;
      }
      robot.measurements.push_back({r[0], static_cast<int>(r[1]), r[2], r[3]});
    }
    if (robot.groundtruth.empty()) throw MrclamError("'" + prefix + "Groundtruth.dat' has no data rows");
    const auto by_time = [](const auto& a, const auto& b) { return a.time_s < b.time_s; };
    std::stable_sort(robot.groundtruth.begin(), robot.groundtruth.end(), by_time);
    std::stable_sort(robot.odometry.begin(), robot.odometry.end(), by_time);
    std::stable_sort(robot.measurements.begin(), robot.measurements.end(), by_time);
    data.start_time_s = std::min(data.start_time_s, robot.groundtruth.front().time_s);
    data.robots[subject] = std::move(robot);
  }
  if (robot_subjects.empty()) data.start_time_s = 0.0;
  return data;
}

common::Pose2 InterpolatePose(const std::vector<MrclamPose>& groundtruth, double time_s) {
  if (groundtruth.empty()) return {};
  if (time_s <= groundtruth.front().time_s) return groundtruth.front().pose;
  if (time_s >= groundtruth.back().time_s) return groundtruth.back().pose;
  const auto after = std::upper_bound(groundtruth.begin(), groundtruth.end(), time_s,
                                      [](double t, const MrclamPose& p) { return t < p.time_s; });
  const auto before = after - 1;
  const double span = after->time_s - before->time_s;
  const double f = span > 0.0 ? (time_s - before->time_s) / span : 0.0;
  const common::Pose2& a = before->pose;
  const common::Pose2& b = after->pose;
  return {a.x + f * (b.x - a.x), a.y + f * (b.y - a.y),
          common::WrapAngle(a.heading + f * common::WrapAngle(b.heading - a.heading))};
}

}  // namespace mrslam::world_sim
