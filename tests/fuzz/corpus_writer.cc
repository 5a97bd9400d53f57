// Writes the seed corpus of the message fuzzers: well-formed samples, each as its fuzzer reads
// it (a type byte, then the CDR payload), into OUT/sensor_sample/ and OUT/peer_message/.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <fastdds/rtps/common/SerializedPayload.h>

#include "common/dds/msg_conversion.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/node/msg_conversion.h"

namespace mrslam::fuzz {
namespace {

template <typename PubSubType>
void Write(const std::string& path, std::uint8_t type_byte, typename PubSubType::type message) {
  PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&message)());
  if (!type.serialize(&message, &payload)) throw std::runtime_error("cannot serialize " + path);
  std::ofstream out(path, std::ios::binary);
  out.put(static_cast<char>(type_byte));
  out.write(reinterpret_cast<const char*>(payload.data), payload.length);
  if (!out) throw std::runtime_error("cannot write " + path);
}

robot_agent::cooperation::PeerHeader Header() { return {"r2", "r1", 4, 2.6, 1}; }

void WriteSensorSamples(const std::string& dir) {
  const common::Stamp stamp{"r1", 5, 3.25};
  common::SensorStep step;
  step.lidar = {stamp, {{3.25, 2.0, 0.1, -1}, {3.25, 4.5, -0.7, 3}}, {{3.25, 3.0, 0.4, "r2"}}};
  step.imu = {stamp, {{3.25, 0.2, 0.1, 0.0}}};
  step.odometry = {stamp, {{2.6, 0.65, 1.0, 0.2}}};
  Write<msg::SensorStepPubSubType>(dir + "/sensors", 0, dds::ToMsg(step));
  msg::StepClock clock;
  clock.stamp(dds::ToMsg(common::Stamp{"world", 5, 3.25}));
  clock.total_steps(100);
  Write<msg::StepClockPubSubType>(dir + "/clock", 1, clock);
}

void WritePeerMessages(const std::string& dir) {
  robot_agent::cooperation::RelativeMeasurement m{
      Header(), true, 3.0, 0.4, {1.0, 2.0, 0.3}, Eigen::Matrix3d::Identity()};
  Write<msg::RelativeMeasurementPubSubType>(dir + "/relative", 0, robot_agent::ToMsg(m));
  robot_agent::cooperation::MapSnapshot snapshot;
  snapshot.header = Header();
  robot_agent::filters::MapLandmark landmark;
  landmark.track_id = 7;
  landmark.mean = Eigen::Vector3d(2.0, 1.0, 0.0);
  landmark.covariance = 0.01 * Eigen::Matrix3d::Identity();
  snapshot.landmarks.push_back(landmark);
  Write<msg::MapSnapshotPubSubType>(dir + "/map", 1, robot_agent::ToMsg(snapshot));
  robot_agent::cooperation::LandmarkMovedNotice notice{Header(), 7, -1, Eigen::Vector2d(2.0, 1.5)};
  Write<msg::LandmarkMovedNoticePubSubType>(dir + "/moved", 2, robot_agent::ToMsg(notice));
  robot_agent::cooperation::FactorBatch batch;
  batch.header = Header();
  batch.opened_by_step = 4;
  batch.holdings = {{"r2", 4, "", 0}};
  batch.heard = {{"r3", 3, {{"r3", 3, "", 0}, {"r2", 2, "r1", 3}}}};
  robot_agent::cooperation::FactorRun run{"r2", 4, {0.0, 0.0, 0.0}, {}, {}};
  common::SensorStep step;
  step.lidar.stamp = {"r2", 4, 2.6};
  step.lidar.landmarks.push_back({2.6, 4.5, -0.7, 3});
  step.lidar.robots.push_back({2.6, 3.0, 0.4, "r1"});
  step.odometry.stamp = step.lidar.stamp;
  step.odometry.segments.push_back({2.0, 0.6, 1.0, 0.2});
  run.steps.push_back(step);
  robot_agent::cooperation::TrackEstimate track;
  track.label = 3;
  track.step = 4;
  track.mean = Eigen::Vector3d(4.0, -2.0, 0.5);
  track.position_covariance = 0.02 * Eigen::Matrix2d::Identity();
  track.heading_var = 0.1;
  run.tracks.push_back(track);
  batch.runs.push_back(run);
  Write<msg::FactorBatchPubSubType>(dir + "/factors", 3, robot_agent::ToMsg(batch));
}

}  // namespace
}  // namespace mrslam::fuzz

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_corpus_writer OUT_DIR\n";
    return 2;
  }
  try {
    const std::string out = argv[1];
    std::filesystem::create_directories(out + "/sensor_sample");
    std::filesystem::create_directories(out + "/peer_message");
    mrslam::fuzz::WriteSensorSamples(out + "/sensor_sample");
    mrslam::fuzz::WritePeerMessages(out + "/peer_message");
  } catch (const std::exception& e) {
    std::cerr << "fuzz_corpus_writer: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
