#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "robot_agent/filters/slam_filter.h"

namespace mrslam::robot_agent::smoother {

// Where a moving landmark is while no reading shows it (docs/smoother.md, "Movers out of sight").
// The front end and the graph predict a mover by its last (v, w) for as long as they hold it; a
// real mover turns, stops and comes back, so extrapolated for long it lands metres off. Here a
// mover's velocity is a first-order Gauss-Markov process of correlation time tau (Singer's
// manoeuvre model): from its state at its last reading (the anchor), its expected motion dies
// out as e^{-t/tau}, so after t it has gone s(t) = tau (1 - e^{-t/tau}) seconds' worth along the
// arc of its (v, w), and each position coordinate's variance has grown by
//   sigma^2 tau^2 (2 t/tau - 3 + 4 e^{-t/tau} - e^{-2 t/tau}),  sigma^2 = v^2 / 2
// (the velocity's stationary variance per axis for a speed v in an unknown direction), besides the
// anchor's covariance carried along the arc and the landmark process noise over t.
// A front end that lost a mover maps it again under a new track; until it lets the old one go,
// the map would hold both: a track read now, first mapped after the older mover's last reading,
// where the older one is predicted (chi-square gate) supersedes it, and the older is no longer
// shown.
class MoverMemory {
 public:
  // tau_s: the correlation time (> 0); landmark_var: the landmark process noise per step of dt_s.
  MoverMemory(double tau_s, const Eigen::Vector3d& landmark_var, double dt_s);

  // Takes in the map the estimator reports for step at time_s (own frame): a moving landmark
  // (confirmed) read since its anchor, or new, is anchored there; one no longer moving or no
  // longer in map is forgotten. An older anchor (not read since) whose prediction to time_s a
  // track read now and first mapped after it was last read lies within the gate gate_d2 of (the
  // sum of both position covariances) is superseded.
  void Remember(const std::vector<filters::MapLandmark>& map, std::uint32_t step, double time_s, double gate_d2);
  // Puts every mover of map that no reading has shown since its anchor at its prediction to
  // time_s, and takes out those superseded.
  void Apply(std::vector<filters::MapLandmark>* map, double time_s) const;

  // The anchor's landmark predicted to time_s.
  filters::MapLandmark Predict(const filters::MapLandmark& anchor, double anchor_time_s, double time_s) const;

  std::size_t size() const { return anchors_.size(); }
  // sizeof(element) * size() of what it holds (a map node's overhead not counted).
  std::size_t Bytes() const { return anchors_.size() * (sizeof(std::uint32_t) + sizeof(Anchor)); }
  void Io(common::Archive& ar) { ar(anchors_); }

 private:
  struct Anchor {
    filters::MapLandmark landmark;
    double time_s = 0.0;
    bool superseded = false;  // another track read since stands for it
    void Io(common::Archive& ar) { ar(landmark, time_s, superseded); }
  };

  double tau_s_;
  Eigen::Vector3d landmark_var_per_s_;
  std::map<std::uint32_t, Anchor> anchors_;  // by track
};

}  // namespace mrslam::robot_agent::smoother
