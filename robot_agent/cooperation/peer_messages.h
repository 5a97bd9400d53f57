#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "common/se2.h"
#include "common/sensor_archive.h"
#include "common/sensor_types.h"
#include "robot_agent/filters/slam_filter.h"

// Plain forms of the peer-to-peer messages (the node converts them to and from DDS). Every
// message names its sender, its recipient, the sender's step when it was sent and a sequence
// number per (sender, recipient).
namespace mrslam::robot_agent::cooperation {

struct PeerHeader {
  std::string sender;
  std::string recipient;
  std::uint32_t step = 0;
  double time_s = 0.0;
  std::uint32_t sequence = 0;
};

// The sender's detection of the recipient at header.step, with the sender's pose estimate.
struct RelativeMeasurement {
  PeerHeader header;
  bool has_range = true;
  double range_m = 0.0;
  double bearing_rad = 0.0;   // the sender's bearing to the recipient
  common::Pose2 sender_pose;  // in the sender's frame
  Eigen::Matrix3d sender_covariance = Eigen::Matrix3d::Identity();
};

// A frame transform an agent holds: T(G_self <- G_peer) with its covariance.
struct FrameTransform {
  std::string peer;
  std::uint32_t step = 0;  // when it was (last) estimated
  common::Pose2 t_self_peer;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

// The sender's map (confirmed landmarks, predicted to header.step) in the sender's frame, and
// the transforms the sender holds to other frames (for chaining). At a rendezvous also the
// sender's history for the joint estimate of the transform: its first pose in its own frame and
// every step from step 1 to header.step (odometry and lidar scan; each landmark detection's
// landmark_id is the sender's track label of it, unlabelled detections left out; no IMU).
struct MapSnapshot {
  PeerHeader header;
  std::vector<filters::MapLandmark> landmarks;
  std::vector<FrameTransform> known_transforms;
  common::Pose2 first_pose;
  std::vector<common::SensorStep> history;
};

// "Landmark moved": the sender saw one of its mapped landmarks move (paper B).
struct LandmarkMovedNotice {
  PeerHeader header;
  std::uint32_t track_id = 0;
  int landmark_id = -1;
  Eigen::Vector2d position_in_sender = Eigen::Vector2d::Zero();
};

// The origin's estimate, in its own frame, of the landmark it labels `label` in its shared steps,
// as of its step `step` (one that read it): shared beside the steps so that every agent can show
// the landmarks its peers map (docs/cooperation.md, "Peers' landmarks streamed"). Not a
// measurement: no graph takes it in.
struct TrackEstimate {
  std::uint32_t label = 0;
  std::uint32_t step = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();  // x_m, y_m, heading_rad
  // The position block and the heading variance (the cross terms are not shared).
  Eigen::Matrix2d position_covariance = Eigen::Matrix2d::Identity();
  double heading_var = 0.0;
  double v_mps = 0.0;
  double w_radps = 0.0;
  bool moving = false;

  void Io(common::Archive& ar) { ar(label, step, mean, position_covariance, heading_var, v_mps, w_radps, moving); }
};

// Raw measurements shared (factor_exchange.h). A run of one origin's steps in a batch: first_step .. first_step +
// steps.size() - 1.
struct FactorRun {
  std::string origin;
  std::uint32_t first_step = 1;
  common::Pose2 first_pose;  // the origin's first pose in its own frame
  std::vector<common::SensorStep> steps;
  std::vector<TrackEstimate> tracks;  // the origin's newest estimates made at these steps
};

// How many steps of an origin the sender holds, and who last sent it new ones of that origin at
// which of the sender's steps (empty, 0: nobody, or they are its own).
struct FactorHolding {
  std::string origin;
  std::uint32_t steps = 0;
  std::string fed_by;
  std::uint32_t fed_at = 0;
};

// What another robot said it holds in its batch of its step `step` (to whichever peer), passed on.
struct HeardHoldings {
  std::string robot;
  std::uint32_t step = 0;
  std::vector<FactorHolding> holdings;
};

// What one agent sends another after a step: the steps the recipient lacks, as far as the sender
// knows, and what the sender holds (so that the recipient sends only what it lacks in turn), and
// what the sender last heard other robots hold (so that the recipient knows it of robots that do
// not send to it). opened_by_step: the sender's step whose scan detected the recipient, which
// opened the exchange.
struct FactorBatch {
  PeerHeader header;
  std::uint32_t opened_by_step = 0;
  std::vector<FactorHolding> holdings;
  std::vector<HeardHoldings> heard;
  std::vector<FactorRun> runs;
  // The sender's step opened_by_step when the recipient may not hold it and the runs do not
  // carry it (so that the recipient can check the detection), else empty.
  std::vector<common::SensorStep> opening;
};

// What an agent sends after a step.
struct PeerOutbox {
  std::vector<RelativeMeasurement> measurements;
  std::vector<MapSnapshot> maps;
  std::vector<LandmarkMovedNotice> moved;
  std::vector<FactorBatch> factors;
};

// What an agent received from its peers during the previous step.
using PeerInbox = PeerOutbox;

// A rendezvous as it appears in the estimate stream and the log.
struct RendezvousEvent {
  std::string peer;
  std::uint32_t step = 0;  // the step of the encounter's first mutual detection
  common::Pose2 t_self_peer;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

// The messages in an Archive (a snapshot of what an agent received but has not applied yet).
inline void Io(common::Archive& ar, PeerHeader& h) { ar(h.sender, h.recipient, h.step, h.time_s, h.sequence); }
inline void Io(common::Archive& ar, RelativeMeasurement& m) {
  ar(m.header, m.has_range, m.range_m, m.bearing_rad, m.sender_pose, m.sender_covariance);
}
inline void Io(common::Archive& ar, FrameTransform& t) { ar(t.peer, t.step, t.t_self_peer, t.covariance); }
inline void Io(common::Archive& ar, MapSnapshot& m) {
  ar(m.header, m.landmarks, m.known_transforms, m.first_pose, m.history);
}
inline void Io(common::Archive& ar, LandmarkMovedNotice& n) {
  ar(n.header, n.track_id, n.landmark_id, n.position_in_sender);
}
inline void Io(common::Archive& ar, FactorRun& r) { ar(r.origin, r.first_step, r.first_pose, r.steps, r.tracks); }
inline void Io(common::Archive& ar, FactorHolding& h) { ar(h.origin, h.steps, h.fed_by, h.fed_at); }
inline void Io(common::Archive& ar, HeardHoldings& h) { ar(h.robot, h.step, h.holdings); }
inline void Io(common::Archive& ar, FactorBatch& b) {
  ar(b.header, b.opened_by_step, b.holdings, b.heard, b.runs, b.opening);
}

inline void Io(common::Archive& ar, PeerOutbox& o) { ar(o.measurements, o.maps, o.moved, o.factors); }
inline void Io(common::Archive& ar, RendezvousEvent& e) { ar(e.peer, e.step, e.t_self_peer, e.covariance); }

}  // namespace mrslam::robot_agent::cooperation
