#include "robot_agent/cooperation/joint_chains.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include <Eigen/Cholesky>

#include "common/gaussian.h"
#include "robot_agent/smoother/levenberg_marquardt.h"

namespace mrslam::robot_agent::cooperation {

std::optional<int> TrackKinematics(const FilterOptions& filter, const filters::MapLandmark& l) {
  if (l.motion == filters::LandmarkMotionKind::kStatic) return kStaticKinematics;
  if (l.motion != filters::LandmarkMotionKind::kUnicycle || (l.v_mps == 0.0 && l.w_radps == 0.0)) return std::nullopt;
  // The filter's (v, w) is a weighted mean over its particles' candidates: the nearest one.
  const int c = filters::NearestKnownKinematics(filter.known_kinematics, l.v_mps, l.w_radps);
  if (c < 0) return std::nullopt;
  return c;
}

smoother::BatchSmoother::Kinematics KinematicsOf(const FilterOptions& filter, int index) {
  if (index < 0 || index >= static_cast<int>(filter.known_kinematics.size())) return {};
  const KnownKinematics& k = filter.known_kinematics[index];
  return {k.v_mps == 0.0 && k.w_radps == 0.0, k.v_mps, k.w_radps};
}

common::SensorStep Relabelled(const common::SensorStep& step, const std::map<int, int>& labels) {
  common::SensorStep out = step;
  out.lidar.landmarks.clear();
  for (auto d : step.lidar.landmarks) {
    const auto it = labels.find(d.landmark_id);
    if (it == labels.end()) continue;
    d.landmark_id = it->second;
    out.lidar.landmarks.push_back(d);
  }
  return out;
}

std::optional<int> KeptKinematics(std::optional<int> seen_moving, std::optional<int> now) {
  return seen_moving && (!now || *now == kStaticKinematics) ? seen_moving : now;
}

bool JointAmongMovers(const AgentOptions& options) {
  return options.cooperation.share_factors &&
         options.filter.landmark_kinematics == LandmarkKinematics::kKnownCandidates;
}

JointChains::JointChains(const AgentOptions& options) : options_(options) {}

void JointChains::Remember(const filters::FilterEstimate& own) {
  for (const auto& l : own.landmarks) {
    const auto k = TrackKinematics(options_.filter, l);
    if (const int label = OwnLabel(l); k && *k != kStaticKinematics && label != 0) seen_moving_[label] = *k;
  }
}

std::optional<int> JointChains::SeenMoving(int label) const {
  const auto it = seen_moving_.find(label);
  return it == seen_moving_.end() ? std::nullopt : std::optional<int>(it->second);
}

JointChains::Problem JointChains::Pose(const filters::FilterEstimate& own, const std::map<std::string, FactorLog>& logs,
                                       const PeerTrackLinks& links, const std::vector<FrameTransform>& frames) const {
  Problem p;
  p.robots.push_back(options_.robot_id);
  std::map<int, int>& own_labels = p.labels[options_.robot_id];
  for (const auto& l : own.landmarks) {
    const int label = OwnLabel(l);
    if (label == 0) continue;
    if (const auto k = KeptKinematics(SeenMoving(label), TrackKinematics(options_.filter, l))) {
      own_labels[label] = label;
      p.kinematics[label] = *k;
    }
  }
  const bool identities = options_.sensors.lidar.report_identity;
  int next = p.kinematics.empty() ? 1 : p.kinematics.rbegin()->first + 1;
  for (const auto& [id, log] : logs) {
    const std::string& peer = id;
    const bool frame_known =
        std::any_of(frames.begin(), frames.end(), [&](const FrameTransform& f) { return f.peer == peer; });
    const auto tracks = links.find(peer);
    if (peer == options_.robot_id || log.Held() == 0 || !frame_known) continue;
    if (identities) {  // every robot's labels name the same landmarks
      p.robots.push_back(peer);
      p.labels[peer] = own_labels;
      continue;
    }
    if (tracks == links.end()) continue;
    std::map<int, int> labels, kinematics;
    bool shared = false;  // without a landmark both read, little but the odometry places the peer
    int label = next;
    for (const auto& [track, link] : tracks->second) {
      std::uint32_t own_track = link.own_track;
      if (const auto it = learned_.find({peer, track});
          own_labels.count(static_cast<int>(own_track)) == 0 && it != learned_.end()) {
        own_track = it->second;
      }
      const auto mine = own_labels.find(static_cast<int>(own_track));
      if (own_track != 0 && mine != own_labels.end()) {
        labels[track] = mine->second;
        shared = true;
      } else {
        labels[track] = label;
        kinematics[label++] = link.kinematics;
      }
    }
    if (!shared) continue;
    next = label;
    p.robots.push_back(peer);
    p.labels[peer] = std::move(labels);
    p.kinematics.insert(kinematics.begin(), kinematics.end());
  }
  return p;
}

int JointChains::OwnLabel(const filters::MapLandmark& l) const {
  if (options_.sensors.lidar.report_identity) return l.landmark_id >= 0 ? l.landmark_id + 1 : 0;
  // Far below the largest int, so that the labels given to peers' tracks above them fit.
  return l.track_id <= kMaxOwnLabel ? static_cast<int>(l.track_id) : 0;
}

std::map<int, int> JointChains::SameLandmarks(const Problem& before, const Problem& now) {
  std::map<int, int> same;
  for (const auto& id : now.robots) {
    const auto old = before.labels.find(id);
    if (old == before.labels.end()) continue;
    for (const auto& [track, label] : now.labels.at(id)) {
      const auto it = old->second.find(track);
      if (it != old->second.end()) same.emplace(label, it->second);
    }
  }
  return same;
}

void JointChains::Build(const std::map<std::string, FactorLog>& logs, const std::vector<FrameTransform>& frames) {
  std::vector<smoother::BatchSmoother::RobotStart> starts;
  first_poses_.clear();
  for (const auto& id : problem_.robots) {
    const common::Pose2& first = logs.at(id).first_pose;
    first_poses_.push_back(first);
    const auto f = std::find_if(frames.begin(), frames.end(), [&](const FrameTransform& t) { return t.peer == id; });
    starts.push_back({id, f == frames.end() ? first : common::Compose(f->t_self_peer, first)});
  }
  std::map<int, smoother::BatchSmoother::Kinematics> kinematics;
  for (const auto& [label, index] : problem_.kinematics) kinematics[label] = KinematicsOf(options_.filter, index);
  smoother_ = std::make_unique<smoother::BatchSmoother>(options_, starts, std::move(kinematics),
                                                        options_.rendezvous.enable_from_step);
  // Each solve ends where the cost stops falling, as the online smoother's do.
  smoother_->SetRelativeCostTolerance(smoother::LeastSquares{}.min_relative_decrease);
  added_.assign(problem_.robots.size(), 0);
}

void JointChains::AddNew(const std::map<std::string, FactorLog>& logs, bool cold) {
  std::vector<const FactorLog*> held;
  std::uint32_t horizon = 0;
  for (const auto& id : problem_.robots) {
    held.push_back(&logs.at(id));
    horizon = std::max(horizon, held.back()->Held());
  }
  const std::uint32_t from = *std::min_element(added_.begin(), added_.end()) + 1;
  // Cold (nothing to start from but the odometry), solved as it grows so that each solve starts
  // near its answer: after 5 steps, then whenever the steps have grown by a quarter.
  std::uint32_t next_solve = 5;
  for (std::uint32_t t = from; t <= horizon; ++t) {
    for (std::size_t r = 0; r < held.size(); ++r) {
      if (added_[r] + 1 != t || t > held[r]->Held()) continue;
      smoother_->Add(static_cast<int>(r), Relabelled(held[r]->steps[t - 1], problem_.labels.at(problem_.robots[r])));
      added_[r] = t;
    }
    if (cold && t == next_solve && t < horizon) {
      smoother_->Solve();
      next_solve = std::max(next_solve + 5, t * 5 / 4);
    }
  }
}

std::optional<JointChains::OwnPose> JointChains::Update(std::uint32_t k, const filters::FilterEstimate& own,
                                                        const std::map<std::string, FactorLog>& logs,
                                                        const PeerTrackLinks& links,
                                                        const std::vector<FrameTransform>& frames) {
  const auto self = logs.find(options_.robot_id);
  if (self == logs.end() || self->second.Held() != k ||
      k > static_cast<std::uint32_t>(options_.cooperation.max_history_steps)) {
    return std::nullopt;
  }
  Remember(own);
  Problem p = Pose(own, logs, links, frames);
  if (p.robots.size() < 2) return std::nullopt;
  if (!smoother_ || !(p == problem_)) {
    // Built again, started from the last solution where the two problems share unknowns.
    const auto previous = std::move(smoother_);
    const Problem before = std::move(problem_);
    problem_ = std::move(p);
    Build(logs, frames);
    AddNew(logs, !previous);
    if (previous) smoother_->StartFrom(*previous, SameLandmarks(before, problem_));
  } else {
    AddNew(logs, false);
  }
  smoother_->Solve();
  const common::Pose2& pose = smoother_->Pose(0);
  Learn(own);
  return OwnPose{pose, smoother_->PoseCovariance(0)};
}

void JointChains::Learn(const filters::FilterEstimate& own) {
  std::map<int, Eigen::Vector2d> at;  // label -> its position at the newest step held
  for (const auto& [position, label] : smoother_->Landmarks()) at[label] = position;
  const std::map<int, int>& own_labels = problem_.labels.at(options_.robot_id);
  const double gate = common::ChiSquare2Quantile(options_.cooperation.match_gate_probability);
  for (std::size_t r = 1; r < problem_.robots.size(); ++r) {
    const std::map<int, int>& labels = problem_.labels.at(problem_.robots[r]);
    std::set<int> used;  // the own labels this robot's tracks already stand on: one track each
    for (const auto& [track, label] : labels) {
      if (own_labels.count(label) != 0) used.insert(label);
    }
    for (const auto& [track, label] : labels) {
      if (own_labels.count(label) != 0 || at.count(label) == 0) continue;
      // The own tracks of the same kinematics within the gate of it (the own landmark's
      // covariance taken for both): the nearest, if it is the only one.
      int best = 0, within = 0;
      double best_d2 = gate;
      for (const auto& l : own.landmarks) {
        const auto mine = own_labels.find(OwnLabel(l));
        if (mine == own_labels.end() || used.count(mine->second) != 0 || at.count(mine->second) == 0 ||
            problem_.kinematics.at(mine->second) != problem_.kinematics.at(label)) {
          continue;
        }
        const Eigen::Vector2d d = at.at(label) - at.at(mine->second);
        const Eigen::Matrix2d s = 2.0 * l.covariance.topLeftCorner<2, 2>();
        const double d2 = d.dot(s.ldlt().solve(d));
        if (!std::isfinite(d2) || d2 > gate) continue;
        ++within;
        if (d2 <= best_d2) {
          best_d2 = d2;
          best = mine->second;
        }
      }
      if (within == 1) {
        learned_[{problem_.robots[r], track}] = static_cast<std::uint32_t>(best);
        used.insert(best);
      }
    }
  }
}

JointEstimate JointChains::Summary() const {
  JointEstimate out;
  if (!smoother_) return out;
  const auto& path = smoother_->Path(0);
  for (std::size_t t = 0; t < path.size(); ++t) out.path.emplace_back(static_cast<int>(t), path[t]);
  for (std::size_t r = 1; r < problem_.robots.size(); ++r) {
    const int i = static_cast<int>(r);
    const common::Pose2 first_inverse = common::Inverse(first_poses_[r]);
    const Eigen::Matrix3d j = common::ComposeJacobianLeft(smoother_->FirstPose(i), first_inverse);
    Eigen::Matrix3d covariance = j * smoother_->FirstPoseCovariance(i) * j.transpose();
    covariance = 0.5 * (covariance + covariance.transpose()).eval();
    out.frames.push_back({problem_.robots[r], common::Compose(smoother_->FirstPose(i), first_inverse), covariance});
  }
  return out;
}

}  // namespace mrslam::robot_agent::cooperation
