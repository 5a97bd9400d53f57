#include "world_sim/replay/mrclam_replay.h"

#include <cmath>
#include <limits>
#include <set>

namespace mrslam::world_sim {

int MrclamSubject(const std::string& robot_id) {
  if (robot_id.size() < 2 || robot_id.size() > 4 || robot_id[0] != 'r' || robot_id[1] == '0') return -1;
  if (robot_id.find_first_not_of("0123456789", 1) != std::string::npos) return -1;
  return std::stoi(robot_id.substr(1));
}

MrclamReplay::MrclamReplay(const common::ScenarioOptions& options) : options_(options) {
  std::vector<int> subjects;
  for (const auto& r : options_.robots) {
    const int subject = MrclamSubject(r.id);
    if (subject < 0) throw MrclamError("replayed robot id '" + r.id + "' is not r<n> (MRCLAM subject n)");
    subjects.push_back(subject);
  }
  data_ = ReadMrclamDataset(options_.replay.dir, subjects);
  const double window_start = UnixTime(0);
  for (std::size_t i = 0; i < options_.robots.size(); ++i) {
    const auto& r = options_.robots[i];
    ReplayRobot robot;
    robot.id = r.id;
    robot.subject = subjects[i];
    // G_i such that the robot's true pose in G_i at the window start is the scenario's
    // inverse(frame) * pose (the origin by default): G_i = first_pose * inverse(pose_in_G_i).
    const common::Pose2 first = InterpolatePose(data_.robots.at(robot.subject).groundtruth, window_start);
    const common::Pose2 pose_in_frame = common::Compose(common::Inverse(r.frame_in_world), r.initial_pose);
    robot.frame_in_world = common::Compose(first, common::Inverse(pose_in_frame));
    robots_.push_back(robot);
  }
}

double MrclamReplay::UnixTime(std::uint32_t k) const {
  return data_.start_time_s + options_.replay.start_s + k * options_.replay.step_s;
}

double MrclamReplay::time_s() const { return options_.replay.start_s + step_ * options_.replay.step_s; }

common::Odometry MrclamReplay::Commands(const MrclamRobot& data, ReplayRobot* robot, double from, double to) const {
  common::Odometry odometry;
  const double t0 = data_.start_time_s;
  const auto& c = data.odometry;
  const auto push = [&](double start, double end, double v, double w) {
    if (end > start) odometry.segments.push_back({start - t0, end - start, v, w});
  };
  if (c.empty() || to <= c.front().time_s) {
    push(from, to, 0.0, 0.0);  // before the first command: standing still
    return odometry;
  }
  if (from < c.front().time_s) push(from, c.front().time_s, 0.0, 0.0);
  // The command holding at `from`: the last one issued at or before it.
  std::size_t& i = robot->next_command;
  while (i + 1 < c.size() && c[i + 1].time_s <= from) ++i;
  for (std::size_t j = i; j < c.size() && c[j].time_s < to; ++j) {
    const double end = j + 1 < c.size() ? std::min(c[j + 1].time_s, to) : to;
    push(std::max(c[j].time_s, from), end, c[j].v_mps, c[j].w_radps);
  }
  return odometry;
}

std::vector<common::SensorStep> MrclamReplay::Step() {
  ++step_;
  const double from = UnixTime(step_ - 1);
  const double to = UnixTime(step_);
  const double t0 = data_.start_time_s;
  std::set<int> landmark_subjects;
  for (const auto& l : data_.landmarks) landmark_subjects.insert(l.subject);

  std::vector<common::SensorStep> samples;
  for (auto& robot : robots_) {
    const MrclamRobot& data = data_.robots.at(robot.subject);
    common::SensorStep s;
    const common::Stamp stamp{robot.id, step_, time_s()};
    s.lidar.stamp = stamp;
    s.imu.stamp = stamp;
    s.odometry = Commands(data, &robot, from, to);
    s.odometry.stamp = stamp;

    const auto& m = data.measurements;
    std::size_t& i = robot.next_measurement;
    while (i < m.size() && m[i].time_s < from) ++i;  // before the window
    for (; i < m.size() && m[i].time_s < to; ++i) {
      const auto& z = m[i];
      const auto it = data_.subject_of_barcode.find(z.barcode);
      if (it == data_.subject_of_barcode.end()) {
        ++stats_.unknown_barcodes;
        continue;
      }
      const int subject = it->second;
      if (landmark_subjects.count(subject) > 0) {
        s.lidar.landmarks.push_back({z.time_s - t0, z.range_m, z.bearing_rad, subject});
      } else {
        const std::string seen = "r" + std::to_string(subject);
        if (subject == robot.subject || options_.RobotIndex(seen) < 0) {
          ++stats_.robots_not_replayed;
          continue;
        }
        s.lidar.robots.push_back({z.time_s - t0, z.range_m, z.bearing_rad, seen});
      }
      ++stats_.measurements;
    }
    samples.push_back(std::move(s));
  }
  return samples;
}

common::GroundTruth MrclamReplay::Truth() const {
  common::GroundTruth truth;
  truth.stamp = {"world", step_, time_s()};
  const double t = UnixTime(step_);
  for (const auto& robot : robots_) {
    truth.robots.push_back({robot.id, InterpolatePose(data_.robots.at(robot.subject).groundtruth, t), true});
    truth.frames.emplace_back(robot.id, robot.frame_in_world);
  }
  for (const auto& l : data_.landmarks) {
    truth.landmarks.push_back({std::to_string(l.subject), {l.x_m, l.y_m, 0.0}, false});
  }
  return truth;
}

}  // namespace mrslam::world_sim
