#include "robot_agent/smoother/mover_memory.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Cholesky>

namespace mrslam::robot_agent::smoother {

using filters::MapLandmark;

MoverMemory::MoverMemory(double tau_s, const Eigen::Vector3d& landmark_var, double dt_s)
    : tau_s_(tau_s), landmark_var_per_s_(landmark_var / dt_s) {}

void MoverMemory::Remember(const std::vector<MapLandmark>& map, std::uint32_t step, double time_s, double gate_d2) {
  std::map<std::uint32_t, Anchor> kept;   // the movers map holds
  std::vector<const MapLandmark*> fresh;  // read now: movers, and static tracks (a mover may look static at first)
  for (const MapLandmark& l : map) {
    if (l.last_seen_step == step && !l.tentative) fresh.push_back(&l);
    if (!l.moving || l.tentative) continue;
    const auto it = anchors_.find(l.track_id);
    if (it == anchors_.end() || it->second.landmark.last_seen_step != l.last_seen_step) {
      kept[l.track_id] = {l, time_s, false};
    } else {
      kept[l.track_id] = it->second;
    }
  }
  anchors_ = std::move(kept);
  // A track read now, first mapped after an older mover (not read since) was last read, where
  // that mover is predicted stands for it: the mover was found again under another track.
  for (auto& [track, anchor] : anchors_) {
    if (anchor.superseded || anchor.time_s >= time_s) continue;
    const MapLandmark now = Predict(anchor.landmark, anchor.time_s, time_s);
    for (const MapLandmark* l : fresh) {
      if (l->track_id == track || l->first_seen_step <= anchor.landmark.last_seen_step) continue;
      const Eigen::Vector2d d = l->mean.head<2>() - now.mean.head<2>();
      const Eigen::Matrix2d s2 = l->covariance.topLeftCorner<2, 2>() + now.covariance.topLeftCorner<2, 2>();
      if (d.dot(s2.ldlt().solve(d)) <= gate_d2) anchor.superseded = true;
    }
  }
}

MapLandmark MoverMemory::Predict(const MapLandmark& anchor, double anchor_time_s, double time_s) const {
  const double t = time_s - anchor_time_s;
  if (!(t > 0.0)) return anchor;
  const double decay = std::exp(-t / tau_s_);
  const double travel_s = tau_s_ * (1.0 - decay);
  const common::LinearizedUnicycleStep step =
      common::UnicycleStepWithJacobians(common::Pose2::FromVector(anchor.mean), anchor.v_mps, anchor.w_radps, travel_s);
  MapLandmark out = anchor;
  out.mean = step.next.Vector();
  out.covariance = step.f * anchor.covariance * step.f.transpose();
  const double sigma2 = 0.5 * anchor.v_mps * anchor.v_mps;
  const double u = t / tau_s_;
  const double spread = sigma2 * tau_s_ * tau_s_ * (2.0 * u - 3.0 + 4.0 * decay - decay * decay);
  out.covariance.diagonal() += landmark_var_per_s_ * t;
  out.covariance(0, 0) += spread;
  out.covariance(1, 1) += spread;
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  out.v_mps = anchor.v_mps * decay;
  out.w_radps = anchor.w_radps * decay;
  return out;
}

void MoverMemory::Apply(std::vector<MapLandmark>* map, double time_s) const {
  for (MapLandmark& l : *map) {
    const auto it = anchors_.find(l.track_id);
    if (l.moving && it != anchors_.end() && it->second.landmark.last_seen_step == l.last_seen_step)
      l = Predict(it->second.landmark, it->second.time_s, time_s);
  }
  map->erase(std::remove_if(map->begin(), map->end(),
                            [&](const MapLandmark& l) {
                              const auto it = anchors_.find(l.track_id);
                              return l.moving && it != anchors_.end() && it->second.superseded;
                            }),
             map->end());
}

}  // namespace mrslam::robot_agent::smoother
