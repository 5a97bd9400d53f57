#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "common/gaussian.h"
#include "common/rng.h"
#include "robot_agent/cooperation/cooperation.h"
#include "robot_agent/filters/map_fusion.h"
#include "robot_agent/filters/slam_filter.h"
#include "tests/robot_agent/pose_sampling.h"

// Cooperation among agents, in process: agents with fake filters in a small world, for the
// protocol's tests and the hostile-input tests.
namespace mrslam::robot_agent::cooperation {

// A filter whose estimate the test sets; merges like FastSLAM's rule for one hypothesis.
class FakeFilter : public filters::SlamFilter {
 public:
  void Process(const common::SensorStep&) override {}
  filters::FilterEstimate Estimate() const override { return estimate; }
  void Io(common::Archive& ar) override { ar(estimate, merges, robot_observations, notices); }
  std::size_t EstimatorBytes() const override { return sizeof(*this) + filters::EstimateBytes(estimate); }
  int MergeLandmarks(const std::vector<filters::MapLandmark>& in, robot_agent::MapFusionRule rule,
                     double gate_probability, double /*too_close_m*/) override {
    ++merges;
    std::vector<filters::MatchCandidate> own, incoming;
    for (const auto& l : estimate.landmarks)
      own.push_back({l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id});
    for (const auto& l : in) incoming.push_back({l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id});
    const std::vector<int> match = filters::MatchLandmarks(own, incoming, common::ChiSquare2Quantile(gate_probability));
    int added = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (match[i] < 0) {
        estimate.landmarks.push_back(in[i]);
        estimate.landmarks.back().track_id = 1000 + added;
        ++added;
        continue;
      }
      filters::MapLandmark& l = estimate.landmarks[match[i]];
      Eigen::Vector2d x = l.mean.head<2>();
      Eigen::Matrix2d p = l.covariance.topLeftCorner<2, 2>();
      filters::FuseObservation<2, 2>(&x, &p, in[i].mean.head<2>(), in[i].covariance.topLeftCorner<2, 2>(), rule);
      l.mean.head<2>() = x;
      l.covariance.topLeftCorner<2, 2>() = p;
    }
    return added;
  }
  bool ObserveKnownRobot(const Eigen::Vector2d&, const Eigen::Matrix2d&, double, double, double) override {
    ++robot_observations;
    return true;
  }
  bool ApplyMovedNotice(const Eigen::Vector2d& position, const Eigen::Matrix2d& cov, double) override {
    notices.emplace_back(position, cov);
    return true;
  }

  filters::FilterEstimate estimate;
  int merges = 0;
  int robot_observations = 0;
  std::vector<std::pair<Eigen::Vector2d, Eigen::Matrix2d>> notices;
};

inline common::ScenarioOptions Scenario(int robots) {
  common::ScenarioOptions s;
  s.name = "cooperation_test";
  const Pose2 frames[3] = {{0.0, 0.0, 0.0}, {0.347, 2.209, -0.6194}, {-3.0, 1.0, 2.0}};
  for (int i = 0; i < robots; ++i) {
    common::RobotOptions r;
    r.id = "r" + std::to_string(i + 1);
    r.frame_in_world = frames[i];
    s.robots.push_back(r);
  }
  s.sensors.lidar.range_noise_sd_m = 0.03;
  s.sensors.lidar.bearing_noise_sd_rad = 0.03;
  s.rendezvous.enable_from_step = 14;
  s.rendezvous.window_steps = 1;
  s.rendezvous.min_interval_steps = 20;
  return s;
}

// N agents with fake filters in a small world; the test says when two robots see each other.
// Pose estimates are the truth in each robot's frame plus noise drawn from the covariance they
// report, so every number the agents exchange is consistent by construction.
class Sim {
 public:
  using Contact = std::function<bool(std::uint32_t step, int i, int j)>;
  Sim(common::ScenarioOptions scenario, Contact contact, std::uint64_t seed)
      : scenario_(std::move(scenario)), contact_(std::move(contact)), rng_(seed, "sim") {
    // Landmarks in W; robot i knows landmarks i and i + 1 (neighbours share one).
    for (int l = 0; l < static_cast<int>(scenario_.robots.size()) + 1; ++l) {
      landmarks_.push_back({3.0 * l - 2.0, 4.0 - l});
    }
    for (std::size_t i = 0; i < scenario_.robots.size(); ++i) {
      agents_.push_back(std::make_unique<Cooperation>(common::AgentOptionsFor(scenario_, scenario_.robots[i].id)));
      filters_.push_back(std::make_unique<FakeFilter>());
      for (std::size_t l = i; l <= i + 1; ++l) {
        filters::MapLandmark m;
        m.track_id = static_cast<std::uint32_t>(l + 1);
        const Eigen::Vector2d p = common::TransformPoint(common::Inverse(Frame(i)), landmarks_[l]);
        m.covariance = Eigen::Vector3d(1e-3, 1e-3, 1.0).asDiagonal();
        m.mean = {p.x() + rng_.Normal(0, std::sqrt(1e-3)), p.y() + rng_.Normal(0, std::sqrt(1e-3)), 0.0};
        filters_[i]->estimate.landmarks.push_back(m);
      }
    }
    inbox_.resize(scenario_.robots.size());
    pose_error_.resize(scenario_.robots.size());
  }

  Pose2 Frame(std::size_t i) const { return scenario_.robots[i].frame_in_world; }
  // Robot i in W at step k: circles near the origin, so every pair is within lidar range.
  Pose2 Truth(std::size_t i, std::uint32_t k) const {
    const double a = 0.15 * k + 2.0 * static_cast<double>(i);
    const Eigen::Vector2d center(1.2 * static_cast<double>(i), 0.5 * static_cast<double>(i));
    return {center.x() + 1.5 * std::cos(a), center.y() + 1.5 * std::sin(a), common::WrapAngle(a + common::kPi / 2)};
  }
  Pose2 TrueTransform(std::size_t i, std::size_t j) const {
    return common::Compose(common::Inverse(Frame(i)), Frame(j));
  }

  void Run(std::uint32_t steps) {
    for (std::uint32_t k = step_ + 1; k <= step_ + steps; ++k) StepOnce(k);
    step_ += steps;
  }

  Cooperation& agent(std::size_t i) { return *agents_[i]; }
  FakeFilter& filter(std::size_t i) { return *filters_[i]; }
  std::uint32_t step() const { return step_; }
  const std::vector<Eigen::Vector2d>& landmarks() const { return landmarks_; }
  // From now on robot i's pose estimates are off by this (in its body frame): a lost robot
  // whose covariance does not say so.
  void SetPoseError(std::size_t i, const Pose2& error) { pose_error_[i] = error; }
  int sent_maps = 0;

 private:
  void StepOnce(std::uint32_t k) {
    const std::size_t n = agents_.size();
    std::vector<PeerInbox> next(n);
    for (std::size_t i = 0; i < n; ++i) {
      agents_[i]->Receive(inbox_[i], filters_[i].get());
      const Eigen::Matrix3d cov = Eigen::Vector3d(4e-4, 4e-4, 1e-4).asDiagonal();
      filters::FilterEstimate& e = filters_[i]->estimate;
      e.step = k;
      e.time_s = 0.65 * k;
      e.covariance = cov;
      e.pose = common::Compose(SamplePose(&rng_, common::Compose(common::Inverse(Frame(i)), Truth(i, k)), cov),
                               pose_error_[i]);
      common::LidarScan scan;
      scan.stamp = {scenario_.robots[i].id, k, e.time_s};
      for (std::size_t j = 0; j < n; ++j) {
        if (j == i || !contact_(k, static_cast<int>(std::min(i, j)), static_cast<int>(std::max(i, j)))) continue;
        const common::RangeBearing z = common::MeasureRangeBearing(Truth(i, k), Truth(j, k).Translation());
        scan.robots.push_back({e.time_s, z.range_m + rng_.Normal(0, 0.03),
                               common::WrapAngle(z.bearing_rad + rng_.Normal(0, 0.03)), scenario_.robots[j].id});
      }
      common::SensorStep step;
      step.lidar = scan;
      const PeerOutbox out = agents_[i]->AfterStep(step, filters_[i]->Estimate());
      for (const auto& m : out.measurements) next[Index(m.header.recipient)].measurements.push_back(m);
      for (const auto& m : out.maps) {
        next[Index(m.header.recipient)].maps.push_back(m);
        ++sent_maps;
      }
    }
    inbox_ = std::move(next);
  }
  std::size_t Index(const std::string& id) const { return static_cast<std::size_t>(scenario_.RobotIndex(id)); }

  common::ScenarioOptions scenario_;
  Contact contact_;
  common::Rng rng_;
  std::vector<Eigen::Vector2d> landmarks_;
  std::vector<std::unique_ptr<Cooperation>> agents_;
  std::vector<std::unique_ptr<FakeFilter>> filters_;
  std::vector<PeerInbox> inbox_;
  std::vector<Pose2> pose_error_;
  std::uint32_t step_ = 0;
};

// The transform an agent holds to peer (a copy), if any.
inline std::optional<FrameTransform> Find(const std::vector<FrameTransform>& ts, const std::string& peer) {
  for (const auto& t : ts) {
    if (t.peer == peer) return t;
  }
  return std::nullopt;
}

}  // namespace mrslam::robot_agent::cooperation
