#include "robot_agent/smoother/joint_graph.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <set>
#include <stdexcept>

#include "common/angles.h"
#include "common/gaussian.h"
#include "robot_agent/filters/odometry_calibration.h"

namespace mrslam::robot_agent::smoother {
namespace {

using common::Pose2;
using common::WrapAngle;

int IndexOf(const std::vector<JointGraph::RobotLog>& logs, const std::string& id) {
  for (std::size_t i = 0; i < logs.size(); ++i) {
    if (logs[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

int Held(const JointGraph::RobotLog& log) { return static_cast<int>(log.steps->size()); }

}  // namespace

JointGraph::JointGraph(const AgentOptions& options, const std::vector<RobotLog>& robots)
    : gap_steps_(std::max(1, options.filter.smoother.max_keyframe_gap_steps)),
      window_steps_(std::max(1, options.rendezvous.window_steps)),
      identities_(options.sensors.lidar.report_identity),
      huber_k_(options.filter.smoother.huber_k),
      gate_(common::ChiSquare2Quantile(options.filter.smoother.reading_gate_probability)),
      robot_var_(options.noise.robot_process_var),
      prior_w_(1.0 / options.filter.smoother.speed_factor_sd, 1.0 / options.filter.smoother.turn_factor_sd,
               1.0 / options.filter.smoother.turn_bias_sd_radps),
      z_w_(ReadingWeights(options.sensors.lidar)),
      options_(options) {
  if (robots.empty()) throw std::invalid_argument("the joint graph needs the agent's own robot");
  for (const auto& log : robots) {
    if (log.steps == nullptr) throw std::invalid_argument("robot " + log.id + " has no steps");
  }
  BuildKeyframes(robots);
  for (const auto& log : robots) last_step_ = std::max(last_step_, Held(log));
  robots_[0].placed = true;
  robots_[0].active = 1;
}

std::vector<int> JointGraph::KeyframeSteps(const std::vector<RobotLog>& logs, int r) const {
  const int n = Held(logs[r]);
  std::set<int> steps{0, n};
  for (int t = gap_steps_; t <= n; t += gap_steps_) steps.insert(t);
  for (int t = 1; t <= n; ++t) {
    const auto& scan = (*logs[r].steps)[t - 1].lidar;
    if (!scan.landmarks.empty()) steps.insert(t);
    for (const auto& d : scan.robots) {
      const int q = IndexOf(logs, d.seen_robot_id);
      if (q >= 0 && q != r && t <= Held(logs[q])) steps.insert(t);
    }
  }
  for (std::size_t q = 0; q < logs.size(); ++q) {  // the steps at which others read r
    if (static_cast<int>(q) == r) continue;
    for (int t = 1; t <= std::min(n, Held(logs[q])); ++t) {
      for (const auto& d : (*logs[q].steps)[t - 1].lidar.robots) {
        if (d.seen_robot_id == logs[r].id) steps.insert(t);
      }
    }
  }
  return {steps.begin(), steps.end()};
}

void JointGraph::BuildKeyframes(const std::vector<RobotLog>& logs) {
  robots_.resize(logs.size());
  for (std::size_t r = 0; r < logs.size(); ++r) {
    Robot& robot = robots_[r];
    robot.id = logs[r].id;
    robot.first_pose = logs[r].first_pose;
    filters::OdometryCalibration calibration(options_.filter);
    const std::vector<int> keyframe_steps = KeyframeSteps(logs, static_cast<int>(r));
    Keyframe first;
    first.pose = robot.first_pose;
    robot.keyframes.push_back(first);
    std::vector<std::vector<Motion>> pending;
    std::size_t next = 1;
    for (int t = 1; t <= Held(logs[r]); ++t) {
      const auto& s = (*logs[r].steps)[t - 1];
      pending.push_back(calibration.Step(s.odometry, s.lidar.stamp.time_s, options_.dt_s));
      if (next >= keyframe_steps.size() || keyframe_steps[next] != t) continue;
      Keyframe kf;
      kf.step = t;
      kf.pose = common::Compose(robot.keyframes.back().pose, OdometryIncrement(pending, robot.correction));
      kf.whitening = Whitening(OdometryCovariance(pending, robot.correction, robot_var_));
      kf.steps = std::move(pending);
      pending.clear();
      robot.keyframe_at[t] = static_cast<int>(robot.keyframes.size());
      robot.keyframes.push_back(std::move(kf));
      ++next;
    }
  }
  for (std::size_t r = 0; r < logs.size(); ++r) AddObservations(logs, static_cast<int>(r));
}

void JointGraph::AddObservations(const std::vector<RobotLog>& logs, int r) {
  for (Keyframe& kf : robots_[r].keyframes) {
    if (kf.step == 0) continue;
    const auto& scan = (*logs[r].steps)[kf.step - 1].lidar;
    for (const auto& d : scan.landmarks) {
      if (d.landmark_id < 1 || !std::isfinite(d.range_m) || !std::isfinite(d.bearing_rad)) continue;
      kf.observations.push_back({LandmarkIndex(r, d.landmark_id), -1, d.range_m, d.bearing_rad, true});
    }
    for (const auto& d : scan.robots) {
      const int q = IndexOf(logs, d.seen_robot_id);
      if (q < 0 || q == r || kf.step > Held(logs[q])) continue;
      if (!std::isfinite(d.range_m) || !std::isfinite(d.bearing_rad)) continue;
      kf.observations.push_back({-1, q, d.range_m, d.bearing_rad, true});
    }
  }
}

int JointGraph::LandmarkIndex(int r, int label) {
  const std::pair<std::string, int> key(identities_ ? std::string() : robots_[r].id, label);
  const auto [it, added] = landmark_index_.emplace(key, static_cast<int>(landmarks_.size()));
  if (added) {
    landmarks_.emplace_back(Eigen::Vector2d::Zero());
    landmark_started_.push_back(false);
  }
  return it->second;
}

const JointGraph::Observation* JointGraph::ReadingOf(int r, int step, int seen) const {
  const auto it = robots_[r].keyframe_at.find(step);
  if (it == robots_[r].keyframe_at.end()) return nullptr;
  for (const auto& o : robots_[r].keyframes[it->second].observations) {
    if (o.seen == seen) return &o;
  }
  return nullptr;
}

bool JointGraph::Place(int horizon) {
  bool any = false;
  for (bool placed_one = true; placed_one;) {
    placed_one = false;
    for (int r = 1; r < Robots(); ++r) {
      if (robots_[r].placed) continue;
      std::optional<Mutual> best;
      for (int q = 0; q < Robots(); ++q) {
        if (!robots_[q].placed) continue;
        for (const Keyframe& kf : robots_[q].keyframes) {
          if (kf.step > horizon || ReadingOf(q, kf.step, r) == nullptr) continue;
          for (int t = kf.step - window_steps_; t <= std::min(horizon, kf.step + window_steps_); ++t) {
            if (ReadingOf(r, t, q) == nullptr) continue;
            const Mutual m{q, r, kf.step, t};
            const auto key = [](const Mutual& x) { return std::make_pair(std::abs(x.step_by - x.step_of), x.step_by); };
            if (!best || key(m) < key(*best)) best = m;
          }
        }
      }
      if (best && PlaceFrom(*best)) placed_one = true;
    }
    any = any || placed_one;
  }
  return any;
}

void JointGraph::Extend(int horizon) {
  for (Robot& robot : robots_) {
    if (!robot.placed) continue;
    while (robot.active < static_cast<int>(robot.keyframes.size()) && robot.keyframes[robot.active].step <= horizon) {
      Keyframe& kf = robot.keyframes[robot.active];
      kf.pose = common::Compose(robot.keyframes[robot.active - 1].pose, OdometryIncrement(kf.steps, robot.correction));
      ++robot.active;
    }
  }
}

void JointGraph::Activate(int horizon) {
  Extend(horizon);
  if (Place(horizon)) Extend(horizon);
  StartLandmarks();
  MakeLayout();
}

bool JointGraph::TargetActive(const Observation& o, int step) const {
  if (o.landmark >= 0) return landmark_col_[o.landmark] >= 0;
  const Robot& seen = robots_[o.seen];
  return seen.placed && seen.keyframe_at.at(step) < seen.active;
}

bool JointGraph::PlaceFrom(const Mutual& m) {
  Robot& r = robots_[m.of];
  const Robot& q = robots_[m.by];
  const Observation* by = ReadingOf(m.by, m.step_by, m.of);
  const Observation* of = ReadingOf(m.of, m.step_of, m.by);
  const auto q_at = [&](int step) { return q.keyframes[q.keyframe_at.at(step)].pose; };
  const Eigen::Vector2d p = common::PointFromRangeBearing(q_at(m.step_by), {by->range_m, by->bearing_rad});
  const Eigen::Vector2d q_seen = q_at(m.step_of).Translation();
  const double heading = WrapAngle(std::atan2(q_seen.y() - p.y(), q_seen.x() - p.x()) - of->bearing_rad);
  const Pose2 own_frame_pose = r.keyframes[r.keyframe_at.at(m.step_by)].pose;
  const Pose2 frame = common::Compose(Pose2{p.x(), p.y(), heading}, common::Inverse(own_frame_pose));
  if (!std::isfinite(frame.x) || !std::isfinite(frame.y) || !std::isfinite(frame.heading)) return false;
  for (Keyframe& kf : r.keyframes) kf.pose = common::Compose(frame, kf.pose);
  r.placed = true;
  r.active = 1;
  return true;
}

void JointGraph::StartLandmarks() {
  for (const Robot& robot : robots_) {
    for (int k = 0; k < robot.active; ++k) {
      const Keyframe& kf = robot.keyframes[k];
      for (const Observation& o : kf.observations) {
        if (o.landmark < 0 || landmark_started_[o.landmark]) continue;
        landmarks_[o.landmark] = common::PointFromRangeBearing(kf.pose, {o.range_m, o.bearing_rad});
        landmark_started_[o.landmark] = true;
      }
    }
  }
}

void JointGraph::MakeLayout() {
  cols_ = 0;
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    Robot& robot = robots_[r];
    if (robot.active == 0) continue;
    robot.pose_col = cols_;
    cols_ += 3 * (robot.active - (r == 0 ? 1 : 0));
    robot.correction_col = cols_;
    cols_ += 3;
  }
  landmark_col_.assign(landmarks_.size(), -1);
  for (std::size_t j = 0; j < landmarks_.size(); ++j) {
    if (!landmark_started_[j]) continue;
    landmark_col_[j] = cols_;
    cols_ += 2;
  }
}

int JointGraph::PoseCol(int r, int k) const {
  if (r == 0 && k == 0) return -1;
  return robots_[r].pose_col + 3 * (k - (r == 0 ? 1 : 0));
}

Eigen::Vector2d JointGraph::Target(const Observation& o, int step) const {
  if (o.landmark >= 0) return landmarks_[o.landmark];
  const Robot& seen = robots_[o.seen];
  return seen.keyframes[seen.keyframe_at.at(step)].pose.Translation();
}

void JointGraph::AddOdometryRows(int r, NormalEquations* rows) const {
  const Robot& robot = robots_[r];
  for (int k = 1; k < robot.active; ++k) {
    const Keyframe& kf = robot.keyframes[k];
    const OdometryFactor f =
        OdometryResidual(robot.keyframes[k - 1].pose, kf.pose, kf.odometry.At(kf.steps, robot.correction), kf.whitening,
                         rows->jacobians);
    rows->cost += f.residual.squaredNorm();
    if (rows->jacobians) {
      rows->Add(f.residual,
                {{PoseCol(r, k - 1), f.d_a}, {PoseCol(r, k), f.d_b}, {robot.correction_col, f.d_correction}});
    }
  }
}

void JointGraph::AddObservationRows(int r, NormalEquations* rows) const {
  const Robot& robot = robots_[r];
  for (int k = 0; k < robot.active; ++k) {
    const Keyframe& kf = robot.keyframes[k];
    for (const Observation& o : kf.observations) {
      if (!o.inlier || !TargetActive(o, kf.step)) continue;
      const Eigen::Vector2d p = Target(o, kf.step);
      const ReadingFactor f = RobustReading(kf.pose, p, o.range_m, o.bearing_rad, z_w_, huber_k_, rows->jacobians);
      rows->cost += f.cost;
      if (!rows->jacobians) continue;
      const int target_col =
          o.landmark >= 0 ? landmark_col_[o.landmark] : PoseCol(o.seen, robots_[o.seen].keyframe_at.at(kf.step));
      NormalEquations::Block jt = NormalEquations::Block::Zero(2, o.landmark >= 0 ? 2 : 3);
      jt.leftCols<2>() = f.d_point;
      rows->Add(f.residual, {{PoseCol(r, k), f.d_pose}, {target_col, jt}});
    }
  }
}

void JointGraph::AddCorrectionPrior(int r, NormalEquations* rows) const {
  const Eigen::Vector3d res = prior_w_.cwiseProduct(robots_[r].correction - Eigen::Vector3d(1.0, 1.0, 0.0));
  rows->AddSquared(res, {{robots_[r].correction_col, Eigen::Matrix3d(prior_w_.asDiagonal())}});
}

NormalEquations JointGraph::Equations(bool jacobians) const {
  NormalEquations rows(cols_, jacobians);
  if (jacobians) rows.h.reserve(triplets_);
  for (int r = 0; r < Robots(); ++r) {
    if (robots_[r].active == 0) continue;
    AddOdometryRows(r, &rows);
    AddObservationRows(r, &rows);
    AddCorrectionPrior(r, &rows);
  }
  if (jacobians) triplets_ = rows.h.size();
  return rows;
}

void JointGraph::Step(const Eigen::VectorXd& delta) {
  for (int r = 0; r < Robots(); ++r) {
    Robot& robot = robots_[r];
    if (robot.active == 0) continue;
    for (int k = 0; k < robot.active; ++k) {
      const int col = PoseCol(r, k);
      if (col >= 0)
        robot.keyframes[k].pose = Pose2::FromVector(robot.keyframes[k].pose.Vector() + delta.segment<3>(col));
    }
    robot.correction += delta.segment<3>(robot.correction_col);
  }
  for (std::size_t j = 0; j < landmarks_.size(); ++j) {
    if (landmark_col_[j] >= 0) landmarks_[j] += delta.segment<2>(landmark_col_[j]);
  }
}

bool JointGraph::UpdateInliers() {
  bool changed = false;
  for (Robot& robot : robots_) {
    for (int k = 0; k < robot.active; ++k) {
      Keyframe& kf = robot.keyframes[k];
      for (Observation& o : kf.observations) {
        if (!TargetActive(o, kf.step)) continue;
        const bool inlier =
            WhitenedReading(kf.pose, Target(o, kf.step), o.range_m, o.bearing_rad, z_w_).squaredNorm() <= gate_;
        changed = changed || inlier != o.inlier;
        o.inlier = inlier;
      }
    }
  }
  return changed;
}

void JointGraph::Solve(bool to_convergence) {
  std::vector<Pose2> saved_poses;
  std::vector<Eigen::Vector3d> saved_corrections;
  std::vector<Eigen::Vector2d> saved_landmarks;
  LeastSquares problem;
  problem.equations = [&](bool jacobians) { return Equations(jacobians); };
  problem.step = [&](const Eigen::VectorXd& delta) { Step(delta); };
  problem.save = [&] {
    saved_poses.clear();
    saved_corrections.clear();
    for (const Robot& robot : robots_) {
      for (const Keyframe& kf : robot.keyframes) saved_poses.push_back(kf.pose);
      saved_corrections.push_back(robot.correction);
    }
    saved_landmarks = landmarks_;
  };
  problem.restore = [&] {
    std::size_t i = 0;
    for (std::size_t r = 0; r < robots_.size(); ++r) {
      for (Keyframe& kf : robots_[r].keyframes) kf.pose = saved_poses[i++];
      robots_[r].correction = saved_corrections[r];
    }
    landmarks_ = saved_landmarks;
  };
  // Solved over a horizon that grows by kSolveEveryS of run time, each solve warm-started from
  // the last: Gauss-Newton from the dead-reckoned paths of a whole run falls into local minima.
  const int every = std::max(1, static_cast<int>(std::lround(kSolveEveryS / options_.dt_s)));
  for (int horizon = std::min(solved_to_ + every, last_step_);; horizon = std::min(horizon + every, last_step_)) {
    Activate(horizon);
    problem.cols = cols_;
    const bool last = to_convergence && horizon == last_step_;
    // The last horizon: loosely while the gate's decisions change, then to convergence (a
    // solution independent of the way to it, to about 1e-7), again while they change.
    const int rounds = last ? kRounds : 1;
    bool tight = false;
    for (int round = 0; round < rounds; ++round) {
      tight = last && (tight || round == rounds - 1);
      problem.min_step = tight ? 1e-9 : 1e-7;
      problem.min_relative_decrease = tight ? 1e-14 : 1e-6;
      auto solver = std::make_shared<Factorization>();
      const LmResult result =
          LevenbergMarquardt(problem, last ? kIterations : kHorizonIterations, kRidge, solver.get());
      const bool changed = UpdateInliers();
      information_ = result.InformationUsable() && !changed ? solver : nullptr;
      if (!changed && (tight || !last)) break;
      tight = tight || !changed;
    }
    if (horizon == last_step_) break;
  }
  solved_to_ = last_step_;
  if (information_ == nullptr) {
    Eigen::SparseMatrix<double> identity(cols_, cols_);
    identity.setIdentity();
    auto fresh = std::make_shared<Factorization>(Equations(true).Matrix() + kRidge * identity);
    if (fresh->info() == Eigen::Success) information_ = std::move(fresh);
  }
}

void JointGraph::WarmStart(const JointGraph& previous) {
  for (Robot& robot : robots_) {
    const auto it = std::find_if(previous.robots_.begin(), previous.robots_.end(),
                                 [&](const Robot& p) { return p.id == robot.id && p.placed; });
    if (it == previous.robots_.end()) continue;
    robot.placed = true;
    robot.correction = it->correction;
    robot.active = 1;
    robot.keyframes.front().pose = it->keyframes.front().pose;
    for (std::size_t k = 1; k < robot.keyframes.size() && robot.keyframes[k].step <= previous.solved_to_; ++k) {
      Keyframe& kf = robot.keyframes[k];
      const auto held = it->keyframe_at.find(kf.step);
      kf.pose = held != it->keyframe_at.end() && held->second < it->active
                    ? it->keyframes[held->second].pose
                    : common::Compose(robot.keyframes[k - 1].pose, OdometryIncrement(kf.steps, robot.correction));
      robot.active = static_cast<int>(k) + 1;
    }
  }
  for (const auto& [key, j] : landmark_index_) {
    const auto held = previous.landmark_index_.find(key);
    if (held == previous.landmark_index_.end() || !previous.landmark_started_[held->second]) continue;
    landmarks_[j] = previous.landmarks_[held->second];
    landmark_started_[j] = true;
  }
  solved_to_ = std::min(previous.solved_to_, last_step_);
}

std::vector<std::pair<int, Pose2>> JointGraph::Path(int r) const {
  std::vector<std::pair<int, Pose2>> out;
  if (!robots_.at(r).placed) return out;
  for (const Keyframe& kf : robots_[r].keyframes) out.emplace_back(kf.step, kf.pose);
  return out;
}

Pose2 JointGraph::Frame(int r) const {
  const Robot& robot = robots_.at(r);
  return common::Compose(robot.keyframes.front().pose, common::Inverse(robot.first_pose));
}

Eigen::Matrix3d JointGraph::FrameCovariance(int r) const {
  const int col = PoseCol(r, 0);
  if (col < 0) return Eigen::Matrix3d::Zero();
  if (!robots_.at(r).placed || information_ == nullptr)
    throw std::logic_error("no covariance: solve a placed robot first");
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(cols_, 3);
  for (int i = 0; i < 3; ++i) unit(col + i, i) = 1.0;
  const Eigen::Matrix3d marginal = information_->solve(unit).middleRows<3>(col);
  const Eigen::Matrix3d j =
      common::ComposeJacobianLeft(robots_[r].keyframes.front().pose, common::Inverse(robots_[r].first_pose));
  return j * marginal * j.transpose();
}

int JointGraph::CountReadings(bool only_outliers) const {
  int n = 0;
  for (const Robot& robot : robots_) {
    for (int k = 0; k < robot.active; ++k) {
      const Keyframe& kf = robot.keyframes[k];
      for (const Observation& o : kf.observations)
        n += (!only_outliers || !o.inlier) && TargetActive(o, kf.step) ? 1 : 0;
    }
  }
  return n;
}

}  // namespace mrslam::robot_agent::smoother
