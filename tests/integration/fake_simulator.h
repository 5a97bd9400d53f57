#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "tests/test_paths.h"

namespace mrslam::testing {

// Stands in for world_sim towards one robot agent: publishes that robot's samples and the step
// clock (with the peer messages the agent must wait for), and reads its acknowledgements.
class FakeSimulator {
 public:
  FakeSimulator(dds::Participant& p, const std::string& robot_id, std::uint32_t total_steps, double dt_s)
      : robot_id_(robot_id),
        total_steps_(total_steps),
        dt_s_(dt_s),
        sensors_(p, dds::SensorTopic(robot_id)),
        clock_(p, dds::kClockTopic),
        ack_(p, dds::AckTopic(robot_id)) {}

  common::Stamp StampOf(std::uint32_t k) const { return {robot_id_, k, dt_s_ * k}; }

  // A sensor step stamped `stamp`: the scan, one odometry segment (v, w) ending at the stamp's
  // time and no IMU reading.
  common::SensorStep SensorStepOf(const common::Stamp& stamp, common::LidarScan scan, double v_mps,
                                  double w_radps) const {
    common::SensorStep step;
    step.lidar = std::move(scan);
    step.lidar.stamp = stamp;
    step.imu.stamp = stamp;
    step.odometry.stamp = stamp;
    step.odometry.segments.push_back({stamp.time_s - dt_s_, dt_s_, v_mps, w_radps});
    return step;
  }

  // Publishes step k (SensorStepOf its stamp), then the clock announcing `deliveries` peer
  // messages for this robot. False if DDS refused a sample.
  bool PublishStep(std::uint32_t k, common::LidarScan scan, double v_mps, double w_radps,
                   const std::vector<std::pair<std::string, std::uint32_t>>& deliveries = {}) {
    const common::Stamp stamp = StampOf(k);
    const bool ok = PublishSensors(SensorStepOf(stamp, std::move(scan), v_mps, w_radps));
    msg::StepClock c;
    c.stamp(dds::ToMsg(common::Stamp{"world", k, stamp.time_s}));
    c.total_steps(total_steps_);
    c.last_step(k == total_steps_);
    for (const auto& [sender, count] : deliveries) {
      msg::PeerDelivery d;
      d.sender_id(sender);
      d.recipient_id(robot_id_);
      d.count(count);
      c.peer_deliveries().push_back(d);
    }
    return clock_.Write(c) && ok;
  }
  bool PublishSensors(const common::SensorStep& step) { return sensors_.Write(dds::ToMsg(step)); }
  // Waits until every reader has acknowledged the sensor steps written so far.
  bool WaitSensorsDelivered() { return sensors_.WaitForAcknowledgments(std::chrono::seconds(20)); }

  // Waits for the agent's acknowledgement of step k; returns its rejected-sample count (-1 on
  // timeout).
  int WaitAck(std::uint32_t k) {
    msg::StepAck a;
    while (ack_.Take(&a, std::chrono::seconds(20))) {
      if (a.stamp().step() == k) return static_cast<int>(a.rejected_samples());
    }
    return -1;
  }

 private:
  std::string robot_id_;
  std::uint32_t total_steps_;
  double dt_s_;
  dds::Writer<msg::SensorStepPubSubType> sensors_;
  dds::Writer<msg::StepClockPubSubType> clock_;
  dds::Reader<msg::StepAckPubSubType> ack_;
};

// The command of a robot_agent for r1 of config/paper_two_robots.yaml on `domain`, fed by a
// FakeSimulator, with extra flags after.
inline std::vector<std::string> R1AgentCommand(int domain, const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {
      BinPath("robot_agent"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--robot", "r1", "--domain",
      std::to_string(domain)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

}  // namespace mrslam::testing
