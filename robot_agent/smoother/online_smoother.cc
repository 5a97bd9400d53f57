#include "robot_agent/smoother/online_smoother.h"

#include <cmath>
#include <map>
#include <set>
#include <utility>

#include "common/angles.h"
#include "common/gaussian.h"
#include "common/se2.h"
#include "robot_agent/filters/fastslam.h"
#include "robot_agent/filters/map_fusion.h"

namespace mrslam::robot_agent::smoother {
namespace {

using common::Pose2;
using filters::FilterEstimate;
using filters::kUnknownHeadingVar;
using filters::MapLandmark;

AgentOptions FrontEndOptions(AgentOptions options) {
  options.filter.particles = options.filter.smoother.front_end_particles;
  return options;
}

// The pose that puts reading points qa, qb (robot frame) on landmarks pa, pb.
Pose2 PoseFromPairs(const Eigen::Vector2d& qa, const Eigen::Vector2d& qb, const Eigen::Vector2d& pa,
                    const Eigen::Vector2d& pb) {
  const Eigen::Vector2d dq = qb - qa, dp = pb - pa;
  const double heading = common::WrapAngle(std::atan2(dp.y(), dp.x()) - std::atan2(dq.y(), dq.x()));
  const double c = std::cos(heading), s = std::sin(heading);
  const Eigen::Vector2d t = pa - Eigen::Vector2d(c * qa.x() - s * qa.y(), s * qa.x() + c * qa.y());
  return {t.x(), t.y(), heading};
}

}  // namespace

OnlineSmoother::OnlineSmoother(const AgentOptions& options, std::uint64_t seed)
    : options_(options),
      front_end_(filters::CreateFastSlam(FrontEndOptions(options), seed)),
      calibration_(options.filter),
      graph_(options, options.initial_pose),
      movers_(options.filter.smoother.mover_memory_s, options.noise.landmark_process_var, options.dt_s) {
  front_ = front_end_->Estimate();
}

bool OnlineSmoother::RemembersMovers() const {
  return options_.filter.smoother.mover_memory_s > 0.0 &&
         options_.filter.landmark_kinematics == LandmarkKinematics::kConstantTurnRate;
}

std::vector<KeyframeGraph::Reading> OnlineSmoother::LabelledReadings(const common::SensorStep& step,
                                                                     const FilterEstimate& front) const {
  std::vector<KeyframeGraph::Reading> out;
  const auto& scan = step.lidar.landmarks;
  for (std::size_t i = 0; i < scan.size() && i < front.detection_tracks.size(); ++i) {
    if (front.detection_tracks[i] != 0)
      out.push_back({front.detection_tracks[i], scan[i].range_m, scan[i].bearing_rad});
  }
  return out;
}

void OnlineSmoother::UpdateTracks(const FilterEstimate& front, const std::vector<KeyframeGraph::Reading>& readings) {
  std::set<std::uint32_t> fixed;
  std::map<std::uint32_t, KeyframeGraph::MoverModel> movers;
  const Pose2 shift = common::Compose(graph_.Pose(), common::Inverse(front.pose));
  std::set<std::uint32_t> mapped;
  for (const auto& l : graph_.Landmarks()) mapped.insert(l.track);
  for (const MapLandmark& l : front.landmarks) {
    // While the readings do not fit the map, new landmarks wait: they could be the old ones seen
    // from a pose gone wrong.
    if (l.tentative || (lost_keyframes_ > 0 && mapped.count(l.track_id) == 0)) continue;
    if (l.motion == filters::LandmarkMotionKind::kStatic) {
      fixed.insert(l.track_id);
    } else if (l.covariance(2, 2) < kUnknownHeadingVar) {
      movers[l.track_id] = {l.v_mps, l.w_radps, common::WrapAngle(l.mean(2) + shift.heading)};
    }
  }
  if (options_.filter.landmark_kinematics == LandmarkKinematics::kKnownCandidates) {
    KeepChains(fixed, &movers);
    JoinRemapped(front, shift, readings, &movers);
    ChooseKinematics(&movers);
  }
  graph_.SetTracks(std::move(fixed), movers);
}

void OnlineSmoother::KeepChains(const std::set<std::uint32_t>& fixed,
                                std::map<std::uint32_t, KeyframeGraph::MoverModel>* movers) const {
  for (const KeyframeGraph::Mover& m : graph_.Movers()) {
    if (movers->count(m.track) == 0 && fixed.count(m.track) == 0) (*movers)[m.track] = graph_.MoverModels().at(m.track);
  }
}

void OnlineSmoother::JoinRemapped(const FilterEstimate& front, const Pose2& shift,
                                  const std::vector<KeyframeGraph::Reading>& readings,
                                  std::map<std::uint32_t, KeyframeGraph::MoverModel>* movers) {
  std::set<std::uint32_t> read_now;
  for (const auto& r : readings) read_now.insert(r.track);
  const double gate_d2 = common::ChiSquare2Quantile(options_.cooperation.match_gate_probability);
  const auto& candidates = options_.filter.known_kinematics;
  const std::vector<KeyframeGraph::Mover> chains = graph_.Movers();
  for (const MapLandmark& l : front.landmarks) {
    const auto model = movers->find(l.track_id);
    if (model == movers->end() || joined_.count(l.track_id) > 0 || graph_.ChainStates(l.track_id) > 0) continue;
    const MapLandmark here = filters::TransformLandmark(l, shift, Eigen::Matrix3d::Zero());
    const Eigen::Vector2d p = here.mean.head<2>();
    const Eigen::Matrix2d p_cov = here.covariance.topLeftCorner<2, 2>();
    const int candidate = filters::NearestKnownKinematics(candidates, model->second.v_mps, model->second.w_radps);
    double best = gate_d2;
    std::uint32_t chain = 0;
    for (const KeyframeGraph::Mover& m : chains) {
      const auto held = kinematics_.find(m.track);
      if (m.track == l.track_id || read_now.count(m.track) > 0 || m.step >= static_cast<int>(l.first_seen_step) ||
          held == kinematics_.end() || held->second != candidate) {
        continue;
      }
      const KeyframeGraph::Prediction at = graph_.PredictMover(m, step_);
      const Eigen::Vector2d d = p - at.state.Translation();
      const double d2 = d.dot((p_cov + at.covariance.topLeftCorner<2, 2>()).ldlt().solve(d));
      if (d2 <= best) {
        best = d2;
        chain = m.track;
      }
    }
    if (chain == 0) continue;
    joined_[l.track_id] = chain;
  }
  for (const auto& [track, chain] : joined_) {
    const auto model = movers->find(track);
    if (model == movers->end()) continue;
    (*movers)[chain] = model->second;
    movers->erase(track);
  }
}

void OnlineSmoother::ChooseKinematics(std::map<std::uint32_t, KeyframeGraph::MoverModel>* movers) {
  const auto& candidates = options_.filter.known_kinematics;
  for (auto& entry : *movers) {
    const std::uint32_t track = entry.first;
    KeyframeGraph::MoverModel& model = entry.second;
    const int states = graph_.ChainStates(track);
    auto held = kinematics_.find(track);
    if (held == kinematics_.end() || states < kMinChoiceStates) {  // the front end's, to begin with
      held =
          kinematics_.insert_or_assign(track, filters::NearestKnownKinematics(candidates, model.v_mps, model.w_radps))
              .first;
    } else if (states < options_.filter.smoother.window_keyframes) {
      const auto cost = [&](std::size_t i) {
        return graph_.TrialCost(track, candidates[i].v_mps, candidates[i].w_radps);
      };
      double best = cost(held->second) - kKinematicsSwitchMargin;
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (static_cast<int>(i) == held->second) continue;
        if (const double c = cost(i); c < best) {
          best = c;
          held->second = static_cast<int>(i);
        }
      }
    }
    model.v_mps = candidates.at(held->second).v_mps;
    model.w_radps = candidates.at(held->second).w_radps;
  }
}

void OnlineSmoother::Process(const common::SensorStep& step) {
  Advance(step);
  if (!RemembersMovers()) return;
  const std::vector<MapLandmark> own = OwnLandmarks(step_);
  const double gate_d2 = common::ChiSquare2Quantile(options_.cooperation.match_gate_probability);
  movers_.Remember(own, front_.step, front_.time_s, gate_d2);
}

void OnlineSmoother::Advance(const common::SensorStep& step) {
  step_ = static_cast<int>(step.lidar.stamp.step);
  front_end_->Process(step);
  front_ = front_end_->Estimate();
  graph_.AddMotion(calibration_.Step(step.odometry, step.lidar.stamp.time_s, options_.dt_s));
  CountPeerMisses(step);
  std::vector<KeyframeGraph::Reading> readings = LabelledReadings(step, front_);
  ++since_keyframe_;
  if (readings.empty() && since_keyframe_ < options_.filter.smoother.max_keyframe_gap_steps) return;
  since_keyframe_ = 0;
  UpdateTracks(front_, readings);
  for (auto& r : readings) {
    if (const auto joined = joined_.find(r.track); joined != joined_.end()) r.track = joined->second;
  }
  graph_.AddKeyframe(step_, readings);
  graph_.Solve();
  CheckLost(step_);
}

void OnlineSmoother::CountPeerMisses(const common::SensorStep& step) {
  if (peers_.size() == 0) return;
  // A reading of a landmark the front end sees move does not explain a static one.
  std::set<std::uint32_t> moving;
  for (const MapLandmark& l : front_.landmarks) {
    if (l.moving) moving.insert(l.track_id);
  }
  std::vector<common::LandmarkDetection> readings;
  const auto& scan = step.lidar.landmarks;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (i >= front_.detection_tracks.size() || moving.count(front_.detection_tracks[i]) == 0)
      readings.push_back(scan[i]);
  }
  // The pose of this step: the graph's newest keyframe moved on by the odometry since.
  const Pose2 pose = graph_.Pose();
  const Eigen::Matrix3d cov = graph_.PoseCovariance();
  peers_.CountMisses(pose, cov.topLeftCorner<2, 2>(), cov(2, 2), readings, options_.sensors.lidar,
                     common::ChiSquare2Quantile(options_.cooperation.match_gate_probability));
}

OnlineSmoother::Support OnlineSmoother::Explain(const Pose2& x) const {
  const auto& lidar = options_.sensors.lidar;
  const double gate = common::ChiSquare2Quantile(options_.filter.smoother.reading_gate_probability);
  const std::vector<KeyframeGraph::Landmark> landmarks = graph_.Landmarks();
  Support out;
  std::set<std::uint32_t> seen;
  for (const auto& [z, inlier] : graph_.NewestReadings()) {
    double best = gate;
    std::uint32_t track = 0;
    for (const auto& l : landmarks) {
      const common::RangeBearing h = common::MeasureRangeBearing(x, l.mean);
      const double dr = (z.range_m - h.range_m) / lidar.range_noise_sd_m;
      const double db = common::WrapAngle(z.bearing_rad - h.bearing_rad) / lidar.bearing_noise_sd_rad;
      if (dr * dr + db * db <= best) {
        best = dr * dr + db * db;
        track = l.track;
      }
    }
    if (track == 0) continue;
    ++out.fit;
    out.labels[z.track] = track;
    seen.insert(track);
  }
  for (const auto& l : landmarks) {
    const common::RangeBearing h = common::MeasureRangeBearing(x, l.mean);
    if (WellInView(h, lidar)) {
      ++out.in_view;
      out.seen += seen.count(l.track) > 0 ? 1 : 0;
    }
  }
  return out;
}

void OnlineSmoother::CheckLost(int step) {
  const auto& o = options_.filter.smoother;
  const int readings = static_cast<int>(graph_.NewestReadings().size());
  const Support now = Explain(graph_.KeyframePose());
  // Suspect: most readings fit no mapped landmark, and most mapped landmarks in view explain no
  // reading (a robot that moved unseen, not one that explores).
  if (readings < o.min_recovery_readings || 2 * now.fit > readings || now.in_view < 2 || 2 * now.seen > now.in_view) {
    lost_keyframes_ = 0;
    lost_since_step_ = -1;
    return;
  }
  if (lost_keyframes_++ == 0) lost_since_step_ = step;
  if (lost_keyframes_ < o.lost_after_keyframes) return;
  // Searched again at every suspect keyframe from then on, as the view brings more of the map
  // in; found, or still not after as many keyframes again, the held landmarks are let in.
  if (Recover(now)) {
    ++recoveries_;
  } else if (lost_keyframes_ < 2 * o.lost_after_keyframes) {
    return;
  }
  lost_keyframes_ = 0;
  lost_since_step_ = -1;
}

bool OnlineSmoother::Recover(const Support& now) {
  const auto readings = graph_.NewestReadings();
  const auto landmarks = graph_.Landmarks();
  const auto& lidar = options_.sensors.lidar;
  std::vector<Eigen::Vector2d> points;
  points.reserve(readings.size());
  for (const auto& [z, inlier] : readings)
    points.push_back(common::PointFromRangeBearing({}, {z.range_m, z.bearing_rad}));
  Support best = now;
  Pose2 best_pose;
  const Pose2 here = graph_.KeyframePose();
  const double max_distance = options_.filter.smoother.max_relocation_m;
  const double tolerance = 6.0 * lidar.range_noise_sd_m + 0.05;
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (std::size_t j = i + 1; j < points.size(); ++j) {
      const double dq = (points[j] - points[i]).norm();
      for (const auto& a : landmarks) {
        for (const auto& b : landmarks) {
          if (a.track == b.track || std::abs((b.mean - a.mean).norm() - dq) > tolerance + 0.05 * dq) continue;
          const Pose2 x = PoseFromPairs(points[i], points[j], a.mean, b.mean);
          if ((x.Translation() - here.Translation()).norm() > max_distance) continue;
          const Support candidate = Explain(x);
          // Better, and the mapped landmarks in view there explain readings (mostly).
          if (candidate.fit > best.fit && 2 * candidate.seen > candidate.in_view) {
            best = candidate;
            best_pose = x;
          }
        }
      }
    }
  }
  const int n = static_cast<int>(readings.size());
  if (best.fit < std::max(options_.filter.smoother.min_recovery_readings, now.fit + 2) || 2 * best.fit <= n)
    return false;
  const Pose2 correction = common::Compose(best_pose, common::Inverse(graph_.KeyframePose()));
  graph_.CutAndMove(lost_since_step_, correction);
  graph_.Relabel(lost_since_step_, best.labels);
  graph_.Solve();
  const Pose2 front_correction = common::Compose(graph_.KeyframePose(), common::Inverse(front_.pose));
  front_end_->Reseat(common::Compose(front_correction, front_.pose), graph_.PoseCovariance());
  front_ = front_end_->Estimate();
  return true;
}

// The front end's landmark of a track (its identity, provenance, motion), or a new one of
// this robot's.
MapLandmark OnlineSmoother::FrontLandmark(std::uint32_t track) const {
  for (const MapLandmark& l : front_.landmarks) {
    if (l.track_id == track) return l;
  }
  MapLandmark m;
  m.track_id = track;
  m.origin_robot = options_.TeamIndex(options_.robot_id);
  m.origin_track = track;
  return m;
}

// The graph's landmarks: the static points and the moving ones predicted to `step`.
std::vector<MapLandmark> OnlineSmoother::GraphLandmarks(int step) const {
  std::vector<MapLandmark> out;
  for (const auto& l : graph_.Landmarks()) {
    MapLandmark m = FrontLandmark(l.track);
    m.mean << l.mean, 0.0;
    m.covariance.setZero();
    m.covariance.topLeftCorner<2, 2>() = l.covariance;
    m.covariance(2, 2) = kUnknownHeadingVar;
    m.motion = filters::LandmarkMotionKind::kStatic;
    m.moving = false;
    m.tentative = false;
    out.push_back(m);
  }
  for (const auto& l : graph_.Movers()) {
    MapLandmark m = FrontLandmark(l.track);
    const KeyframeGraph::Prediction p = graph_.PredictMover(l, step);
    m.mean = p.state.Vector();
    m.covariance = p.covariance;
    if (const auto chosen = kinematics_.find(l.track); chosen != kinematics_.end()) {
      m.v_mps = options_.filter.known_kinematics.at(chosen->second).v_mps;
      m.w_radps = options_.filter.known_kinematics.at(chosen->second).w_radps;
    }
    out.push_back(m);
  }
  return out;
}

void OnlineSmoother::Io(common::Archive& ar) {
  front_end_->Io(ar);
  ar(calibration_, graph_, front_, step_, since_keyframe_, lost_keyframes_, lost_since_step_, recoveries_, peers_,
     movers_, kinematics_, joined_);
}

std::size_t OnlineSmoother::EstimatorBytes() const {
  return sizeof(*this) + front_end_->EstimatorBytes() + filters::EstimateBytes(front_) + graph_.EstimatorBytes() +
         peers_.Bytes() + movers_.Bytes() + filters::ElementBytes(kinematics_) + filters::ElementBytes(joined_);
}

// The own map: the graph's landmarks and the front end's others (not in the graph yet),
// re-anchored: where the front end sees them from its pose, seen from the graph's.
std::vector<MapLandmark> OnlineSmoother::OwnLandmarks(int step) const {
  std::vector<MapLandmark> out = GraphLandmarks(step);
  std::set<std::uint32_t> in_graph;
  for (const MapLandmark& l : out) in_graph.insert(l.track_id);
  const Pose2 shift = common::Compose(graph_.Pose(), common::Inverse(front_.pose));
  for (const MapLandmark& l : front_.landmarks) {
    if (in_graph.count(l.track_id) > 0 || joined_.count(l.track_id) > 0) continue;
    out.push_back(filters::TransformLandmark(l, shift, Eigen::Matrix3d::Zero()));
  }
  return out;
}

FilterEstimate OnlineSmoother::Estimate() const {
  FilterEstimate out;
  out.step = front_.step;
  out.time_s = front_.time_s;
  out.pose = graph_.Pose();
  out.covariance = graph_.PoseCovariance();
  out.effective_sample_size = front_.effective_sample_size;
  out.particles = front_.particles;
  out.labels_detections = true;
  out.detection_tracks = front_.detection_tracks;
  out.landmarks = OwnLandmarks(static_cast<int>(out.step));
  const double gate_d2 = common::ChiSquare2Quantile(options_.cooperation.match_gate_probability);
  if (RemembersMovers()) movers_.Apply(&out.landmarks, out.time_s);
  peers_.AppendUnmatched(&out.landmarks, gate_d2, options_.cooperation.merge_min_separation_m);
  return out;
}

int OnlineSmoother::MergeLandmarks(const std::vector<MapLandmark>& landmarks_in_own_frame, MapFusionRule rule,
                                   double gate_probability, double too_close_m) {
  std::vector<MapLandmark> moving;
  for (const MapLandmark& l : landmarks_in_own_frame) {
    if (l.moving) moving.push_back(l);
  }
  const int added = moving.empty() ? 0 : front_end_->MergeLandmarks(moving, rule, gate_probability, too_close_m);
  return added + peers_.Merge(landmarks_in_own_frame, graph_.KeyframePoses(), options_.sensors.lidar,
                              common::ChiSquare2Quantile(gate_probability), too_close_m);
}

}  // namespace mrslam::robot_agent::smoother
