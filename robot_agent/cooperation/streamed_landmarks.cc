#include "robot_agent/cooperation/streamed_landmarks.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "robot_agent/filters/map_fusion.h"

namespace mrslam::robot_agent::cooperation {
namespace {

// The largest standard deviation of a 2-d covariance (along its major axis).
double LargestSd(const Eigen::Matrix2d& c) {
  return std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(c).eigenvalues()(1)));
}

// Whether a and b stand for the same landmark, or cannot be told apart: the same reported
// identity (two different ones never), the same provenance, else closer than near_m.
bool SameOrNear(const filters::MatchCandidate& a, const filters::MatchCandidate& b, double near_m) {
  if (a.landmark_id >= 0 && b.landmark_id >= 0) return a.landmark_id == b.landmark_id;
  if (a.origin >= 0 && a.origin == b.origin) return true;
  return (a.position - b.position).norm() < near_m;
}

// Half a cell's diagonal: any part of a cell lies within it of the cell's centre.
constexpr double kCellReachM = 0.5 * 1.4142135623730951 * StreamedLandmarks::kCellM;

}  // namespace

StreamedLandmarks::StreamedLandmarks(const AgentOptions& options)
    : options_(options),
      movers_shown_(options.filter.landmark_kinematics == LandmarkKinematics::kConstantTurnRate &&
                    options.filter.smoother.mover_memory_s > 0.0),
      movers_(movers_shown_ ? options.filter.smoother.mover_memory_s : 1.0, options.noise.landmark_process_var,
              options.dt_s),
      reached_(kCellM) {}

void StreamedLandmarks::Observe(const filters::FilterEstimate& estimate) {
  if (!estimate.covariance.allFinite()) return;
  const auto& lidar = options_.sensors.lidar;
  // Any part of a cell within reach of where the robot may have been.
  const double pose_sds = std::min(kReachSds * LargestSd(estimate.covariance.topLeftCorner<2, 2>()), lidar.max_range_m);
  reached_.Mark(estimate.pose, lidar.max_range_m, 0.5 * lidar.fov_rad, kCellReachM + pose_sds);
}

bool StreamedLandmarks::Reached(const filters::MapLandmark& l) const {
  const double sds = kReachSds * LargestSd(l.covariance.topLeftCorner<2, 2>());
  if (sds > options_.sensors.lidar.max_range_m) return true;
  return reached_.AnyWithin(l.mean.head<2>(), sds + kCellReachM);
}

std::optional<filters::MapLandmark> StreamedLandmarks::Placement(const std::string& origin, const FactorLog& log,
                                                                 const TrackEstimate& t, const FrameTransform& frame,
                                                                 double time_s) const {
  // (Labels are checked where an estimate is recorded or received; the step indexes the log.)
  if ((t.moving && !movers_shown_) || t.step == 0 || t.step > log.Held()) return std::nullopt;
  const auto origin_index = static_cast<std::uint32_t>(options_.TeamIndex(origin));
  filters::MapLandmark l;
  l.track_id = kFirstTrack | (origin_index << 20) | t.label;
  l.landmark_id = options_.sensors.lidar.report_identity ? static_cast<int>(t.label) - 1 : -1;
  l.mean = t.mean;
  l.covariance = Eigen::Matrix3d::Zero();
  l.covariance.topLeftCorner<2, 2>() = t.position_covariance;
  l.covariance(2, 2) = t.heading_var;
  l.v_mps = t.v_mps;
  l.w_radps = t.w_radps;
  l.motion = t.moving ? filters::LandmarkMotionKind::kConstantTurnRate : filters::LandmarkMotionKind::kStatic;
  l.moving = t.moving;
  l.first_seen_step = l.last_seen_step = t.step;
  l.origin_robot = static_cast<int>(origin_index);
  l.origin_track = t.label;
  l = filters::TransformLandmark(l, frame.t_self_peer, frame.covariance);
  if (t.moving) l = movers_.Predict(l, log.steps[t.step - 1].lidar.stamp.time_s, time_s);
  if (Reached(l)) return std::nullopt;
  return l;
}

std::vector<StreamedLandmarks::Placed> StreamedLandmarks::Place(const std::map<std::string, FactorLog>& logs,
                                                                const std::vector<FrameTransform>& transforms,
                                                                double time_s) const {
  std::vector<Placed> out;
  for (const FrameTransform& frame : transforms) {
    const auto log = logs.find(frame.peer);
    if (frame.peer == options_.robot_id || log == logs.end()) continue;
    for (const auto& [label, t] : log->second.tracks) {
      if (auto l = Placement(frame.peer, log->second, t, frame, time_s)) out.push_back({t.step, *l});
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const Placed& a, const Placed& b) { return a.step > b.step; });
  return out;
}

void StreamedLandmarks::Append(const std::map<std::string, FactorLog>& logs,
                               const std::vector<FrameTransform>& transforms, filters::FilterEstimate* estimate) const {
  std::vector<filters::MapLandmark>& map = estimate->landmarks;
  std::vector<filters::MatchCandidate> shown;
  shown.reserve(map.size());
  for (const auto& l : map) shown.push_back(filters::CandidateOf(l));
  const double near_m = options_.cooperation.merge_min_separation_m;
  for (const Placed& p : Place(logs, transforms, estimate->time_s)) {
    const filters::MatchCandidate c = filters::CandidateOf(p.landmark);
    if (std::any_of(shown.begin(), shown.end(), [&](const auto& s) { return SameOrNear(s, c, near_m); })) continue;
    shown.push_back(c);
    map.push_back(p.landmark);
  }
}

}  // namespace mrslam::robot_agent::cooperation
