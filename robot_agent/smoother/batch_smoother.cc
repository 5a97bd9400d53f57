#include "robot_agent/smoother/batch_smoother.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "common/angles.h"
#include "common/gaussian.h"
#include "robot_agent/filters/landmark_ekf.h"
#include "robot_agent/filters/slam_filter.h"

namespace mrslam::robot_agent::smoother {
namespace {

using common::Pose2;
using common::WrapAngle;

// A variance used as a whitening divisor: zero (a noise-free model) becomes a stiff tiny one.
double Sd(double var) { return std::sqrt(std::max(var, 1e-12)); }

// a - b on poses, heading wrapped.
Eigen::Vector3d Minus(const Pose2& a, const Pose2& b) {
  return {a.x - b.x, a.y - b.y, WrapAngle(a.heading - b.heading)};
}

}  // namespace

BatchSmoother::BatchSmoother(const AgentOptions& options, const std::vector<RobotStart>& robots,
                             std::map<int, Kinematics> kinematics, int robot_detections_from_step, Unlisted unlisted)
    : dt_s_(options.dt_s),
      filter_(options.filter),
      unlisted_(unlisted),
      robot_var_(options.noise.robot_process_var),
      landmark_var_(options.noise.landmark_process_var),
      var_r_(options.sensors.lidar.range_noise_sd_m * options.sensors.lidar.range_noise_sd_m),
      var_b_(options.sensors.lidar.bearing_noise_sd_rad * options.sensors.lidar.bearing_noise_sd_rad),
      robot_detections_from_step_(robot_detections_from_step),
      kinematics_(std::move(kinematics)) {
  if (robots.empty()) throw std::invalid_argument("the reference needs at least one robot");
  for (const auto& robot : robots) AddRobot(robot);
}

int BatchSmoother::AddRobot(const RobotStart& robot) {
  robots_.push_back({robot.id, {robot.first_pose}, filters::OdometryCalibration(filter_), {}});
  return static_cast<int>(robots_.size()) - 1;
}

Pose2 BatchSmoother::StepLandmark(const Pose2& l, const Kinematics& k) const {
  return k.is_static ? l : common::UnicycleStep(l, k.v_mps, k.w_radps, dt_s_);
}

void BatchSmoother::Add(const std::vector<common::SensorStep>& steps) {
  if (steps.size() != robots_.size()) throw std::invalid_argument("the reference needs one step per robot");
  for (std::size_t r = 0; r < robots_.size(); ++r) AppendPose(static_cast<int>(r), steps[r]);
  ExtendChains();
  for (std::size_t r = 0; r < robots_.size(); ++r) AddReadings(static_cast<int>(r), steps[r]);
}

void BatchSmoother::Add(int r, const common::SensorStep& step) {
  AppendPose(r, step);
  ExtendChains();
  AddReadings(r, step);
}

void BatchSmoother::AppendPose(int r, const common::SensorStep& step) {
  Robot& robot = robots_.at(r);
  const int t = static_cast<int>(robot.path.size());
  robot.motion.push_back(robot.calibration.Step(step.odometry, step.lidar.stamp.time_s, dt_s_));
  robot.path.push_back(common::Compose(robot.path.back(), Increment(robot, t, robot.correction)));
}

void BatchSmoother::AddReadings(int r, const common::SensorStep& step) {
  const int t = Steps(r);
  for (const auto& d : step.lidar.landmarks) AddLandmarkReading(r, t, d);
  if (t < robot_detections_from_step_) return;
  for (const auto& d : step.lidar.robots) {
    for (std::size_t seen = 0; seen < robots_.size(); ++seen) {
      if (static_cast<int>(seen) != r && robots_[seen].id == d.seen_robot_id && std::isfinite(d.range_m) &&
          std::isfinite(d.bearing_rad)) {
        readings_.push_back({t, r, -1, static_cast<int>(seen), d.range_m, d.bearing_rad});
      }
    }
  }
}

int BatchSmoother::Horizon() const {
  int horizon = 0;
  for (int r = 0; r < static_cast<int>(robots_.size()); ++r) horizon = std::max(horizon, Steps(r));
  return horizon;
}

void BatchSmoother::ExtendChains() {
  const int horizon = Horizon();
  for (auto& [id, chain] : chains_) ExtendChain(&chain, horizon);
}

void BatchSmoother::ExtendChain(Chain* chain, int horizon) const {
  if (chain->kinematics.is_static) return;
  while (chain->first_step + static_cast<int>(chain->states.size()) - 1 < horizon) {
    chain->states.push_back(StepLandmark(chain->states.back(), chain->kinematics));
  }
}

void BatchSmoother::PrependChain(Chain* chain, int t) const {
  if (chain->kinematics.is_static || t >= chain->first_step) return;
  const Pose2 back = common::Inverse(StepLandmark(Pose2{}, chain->kinematics));
  std::vector<Pose2> earlier(static_cast<std::size_t>(chain->first_step - t));
  Pose2 l = chain->states.front();
  for (auto it = earlier.rbegin(); it != earlier.rend(); ++it) *it = l = common::Compose(l, back);
  chain->states.insert(chain->states.begin(), earlier.begin(), earlier.end());
  chain->first_step = t;
}

void BatchSmoother::AddLandmarkReading(int r, int t, const common::LandmarkDetection& d) {
  if (d.landmark_id < 0) throw std::invalid_argument("the reference needs detections with identities");
  const bool known = kinematics_.count(d.landmark_id) != 0 || unlisted_ == Unlisted::kStatic;
  if (!known || !std::isfinite(d.range_m) || !std::isfinite(d.bearing_rad)) return;
  readings_.push_back({t, r, d.landmark_id, -1, d.range_m, d.bearing_rad});
  PlaceFrom(readings_.back());
}

void BatchSmoother::PlaceFrom(const Reading& z) {
  const Eigen::Vector2d point =
      common::PointFromRangeBearing(robots_[z.robot].path[z.step], {z.range_m, z.bearing_rad});
  auto [it, created] = chains_.try_emplace(z.landmark_id);
  Chain& chain = it->second;
  if (created) {
    chain.first_step = z.step;
    if (const auto listed = kinematics_.find(z.landmark_id); listed != kinematics_.end()) {
      chain.kinematics = listed->second;
    }
    chain.states.push_back({point.x(), point.y(), 0.0});
    ExtendChain(&chain, Horizon());
  } else {
    // Until the heading is started, every sighting was at the first one's step (two robots may
    // read a landmark at the same step).
    const int seen_at = chain.first_step;
    PrependChain(&chain, z.step);
    if (!chain.heading_started && !chain.kinematics.is_static && z.step != seen_at) {
      StartHeading(&chain, seen_at, z.step, point);
    }
  }
}

// The two sightings a (earlier) and b (later), n = b - a steps apart: the heading at a from the
// chord between them (the chord of the arc turns by w dt / 2 per step less than the heading at
// its end), then the chain again from its first state (at a).
void BatchSmoother::StartHeading(Chain* chain, int seen_at, int t, const Eigen::Vector2d& point) const {
  const Pose2& seen = chain->states[StateIndex(*chain, seen_at)];
  const bool later = t > seen_at;
  const Eigen::Vector2d a = later ? seen.Translation() : point;
  const Eigen::Vector2d b = later ? point : seen.Translation();
  const int steps = later ? t - seen_at : seen_at - t;
  const double chord = std::atan2(b.y() - a.y(), b.x() - a.x());
  Pose2 l{a.x(), a.y(), WrapAngle(chord - 0.5 * chain->kinematics.w_radps * dt_s_ * (steps + 1))};
  for (auto& state : chain->states) {
    state = l;
    l = StepLandmark(l, chain->kinematics);
  }
  chain->heading_started = true;
}

void BatchSmoother::StartFrom(const BatchSmoother& previous, const std::map<int, int>& same_landmark) {
  for (Robot& robot : robots_) {
    const auto old = std::find_if(previous.robots_.begin(), previous.robots_.end(),
                                  [&](const Robot& o) { return o.id == robot.id; });
    if (old == previous.robots_.end()) continue;
    const std::size_t both = std::min(robot.path.size(), old->path.size());
    std::copy(old->path.begin(), old->path.begin() + static_cast<std::ptrdiff_t>(both), robot.path.begin());
    robot.correction = old->correction;
    for (std::size_t t = both; t < robot.path.size(); ++t) {
      robot.path[t] = common::Compose(robot.path[t - 1], Increment(robot, static_cast<int>(t), robot.correction));
    }
  }
  // Every landmark placed again from its readings seen from those poses, then those of the
  // previous problem taken from it.
  chains_.clear();
  for (const Reading& z : readings_) {
    if (z.landmark_id >= 0) PlaceFrom(z);
  }
  for (const auto& [label, old_label] : same_landmark) {
    const auto now = chains_.find(label);
    const auto old = previous.chains_.find(old_label);
    if (now != chains_.end() && old != previous.chains_.end()) StartChainFrom(&now->second, old->second);
  }
}

void BatchSmoother::StartChainFrom(Chain* chain, const Chain& before) const {
  const bool same_kinematics = chain->kinematics.is_static == before.kinematics.is_static &&
                               chain->kinematics.v_mps == before.kinematics.v_mps &&
                               chain->kinematics.w_radps == before.kinematics.w_radps;
  // A heading the previous problem never saw does not replace one started here.
  if (!same_kinematics || (chain->heading_started && !before.heading_started)) return;
  if (chain->kinematics.is_static) {
    chain->states = before.states;
    return;
  }
  // The states of the steps both hold, then on (and back) from them by the kinematics.
  const int end = chain->first_step + static_cast<int>(chain->states.size());
  const int first = std::max(chain->first_step, before.first_step);
  const int last = std::min(end, before.first_step + static_cast<int>(before.states.size())) - 1;
  if (first > last) return;
  for (int t = first; t <= last; ++t) chain->states[StateIndex(*chain, t)] = before.states[StateIndex(before, t)];
  const Pose2 back = common::Inverse(StepLandmark(Pose2{}, chain->kinematics));
  for (int t = first - 1; t >= chain->first_step; --t) {
    chain->states[StateIndex(*chain, t)] = common::Compose(chain->states[StateIndex(*chain, t + 1)], back);
  }
  for (int t = last + 1; t < end; ++t) {
    chain->states[StateIndex(*chain, t)] = StepLandmark(chain->states[StateIndex(*chain, t - 1)], chain->kinematics);
  }
  chain->heading_started = before.heading_started;
}

void BatchSmoother::Solve() {
  SolveOnce();
  for (int round = 0; round < 10 && UpdateInliers(); ++round) SolveOnce();
}

// The index of a landmark's state at step t.
int BatchSmoother::StateIndex(const Chain& chain, int t) {
  return chain.kinematics.is_static ? 0 : t - chain.first_step;
}

Eigen::Vector2d BatchSmoother::Target(const Reading& z) const {
  if (z.landmark_id < 0) return robots_[z.seen].path[z.step].Translation();
  const Chain& chain = chains_.at(z.landmark_id);
  return chain.states[StateIndex(chain, z.step)].Translation();
}

Eigen::Vector2d BatchSmoother::WhitenedResidual(const Reading& z) const {
  const common::RangeBearing h = common::MeasureRangeBearing(robots_[z.robot].path[z.step], Target(z));
  return {(z.range_m - h.range_m) / Sd(var_r_), WrapAngle(z.bearing_rad - h.bearing_rad) / Sd(var_b_)};
}

bool BatchSmoother::UpdateInliers() {
  if (filter_.outlier_gate_probability >= 1.0) return false;
  const double gate = common::ChiSquare2Quantile(filter_.outlier_gate_probability);
  bool changed = false;
  for (Reading& z : readings_) {
    if (!Usable(z)) continue;
    const bool inlier = WhitenedResidual(z).squaredNorm() <= gate;
    changed = changed || inlier != z.inlier;
    z.inlier = inlier;
  }
  return changed;
}

Pose2 BatchSmoother::Increment(const Robot& robot, int t, const Eigen::Vector3d& correction) {
  Pose2 out;
  for (const auto& m : robot.motion[t - 1]) {
    out = common::UnicycleStep(out, correction(0) * m.v_mps, correction(1) * m.w_radps + correction(2), m.dt_s);
  }
  return out;
}

BatchSmoother::Layout BatchSmoother::MakeLayout() const {
  Layout layout;
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    layout.robot_base.push_back(layout.cols);
    const int steps = Steps(static_cast<int>(r));
    layout.cols += 3 * (r == 0 ? steps : steps + 1);
  }
  for (const auto& [id, chain] : chains_) {
    layout.chain_col[id] = layout.cols;
    layout.cols += 3 * static_cast<int>(chain.states.size());
  }
  if (estimate_calibration_) {
    layout.correction_base = layout.cols;
    layout.cols += 3 * static_cast<int>(robots_.size());
  }
  return layout;
}

int BatchSmoother::Layout::RobotCol(int r, int t) const {
  if (r == 0) return t == 0 ? -1 : robot_base[0] + 3 * (t - 1);
  return robot_base[r] + 3 * t;
}

void BatchSmoother::BuildRows(const Layout& layout, NormalEquations* rows) const {
  const Eigen::Vector3d correction_prior(1.0, 1.0, 0.0);
  const Eigen::Vector3d correction_w(1.0 / 0.1, 1.0 / 0.1, 1.0 / 0.05);
  const Eigen::Vector3d robot_w = robot_var_.unaryExpr(&Sd).cwiseInverse();
  const Eigen::Vector3d landmark_w = landmark_var_.unaryExpr(&Sd).cwiseInverse();
  const Eigen::Vector2d z_w(1.0 / Sd(var_r_), 1.0 / Sd(var_b_));
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    const Robot& robot = robots_[r];
    const int ri = static_cast<int>(r);
    for (int t = 1; t <= Steps(ri); ++t) {
      const Pose2 increment = Increment(robot, t, robot.correction);
      const Pose2& previous = robot.path[t - 1];
      const Eigen::Vector3d res = robot_w.asDiagonal() * Minus(robot.path[t], common::Compose(previous, increment));
      const Eigen::Matrix3d jf = -(robot_w.asDiagonal() * common::ComposeJacobianLeft(previous, increment));
      // d increment / d correction by central differences; then through the composition.
      Eigen::Matrix3d jc = Eigen::Matrix3d::Zero();
      if (estimate_calibration_ && rows->jacobians) {
        constexpr double kH = 1e-6;
        for (int c = 0; c < 3; ++c) {
          Eigen::Vector3d d = Eigen::Vector3d::Zero();
          d(c) = kH;
          jc.col(c) =
              Minus(Increment(robot, t, robot.correction + d), Increment(robot, t, robot.correction - d)) / (2.0 * kH);
        }
        jc = -(robot_w.asDiagonal() * common::ComposeJacobianRight(previous, increment) * jc);
      }
      rows->AddSquared(res, {{layout.RobotCol(ri, t), Eigen::Matrix3d(robot_w.asDiagonal())},
                             {layout.RobotCol(ri, t - 1), jf},
                             {layout.CorrectionCol(ri), jc}});
    }
    if (estimate_calibration_) {
      const Eigen::Vector3d res = correction_w.asDiagonal() * (correction_prior - robot.correction);
      rows->AddSquared(res, {{layout.CorrectionCol(ri), -Eigen::Matrix3d(correction_w.asDiagonal())}});
    }
  }
  for (const auto& [id, chain] : chains_) {
    const int base = layout.chain_col.at(id);
    // A weak prior on the first heading keeps it defined before it is observable.
    const Eigen::RowVector3d prior(0.0, 0.0, 1e-3);
    rows->Add(Eigen::Matrix<double, 1, 1>::Zero(), {{base, prior}});
    // A unicycle step is a composition with a fixed increment (a static landmark has one state).
    const Pose2 increment = StepLandmark(Pose2{}, chain.kinematics);
    const Eigen::Vector3d& w = landmark_w;
    for (std::size_t i = 1; i < chain.states.size(); ++i) {
      const Pose2& previous = chain.states[i - 1];
      const Eigen::Vector3d res = w.asDiagonal() * Minus(chain.states[i], common::Compose(previous, increment));
      const Eigen::Matrix3d jf = -(w.asDiagonal() * common::ComposeJacobianLeft(previous, increment));
      const int col = base + 3 * static_cast<int>(i);
      rows->AddSquared(res, {{col, Eigen::Matrix3d(w.asDiagonal())}, {col - 3, jf}});
    }
  }
  for (const Reading& z : readings_) {
    if (!z.inlier || !Usable(z)) continue;
    const Pose2& x = robots_[z.robot].path[z.step];
    const Eigen::Vector2d p = Target(z);
    const int target_col = z.landmark_id >= 0
                               ? layout.chain_col.at(z.landmark_id) + 3 * StateIndex(chains_.at(z.landmark_id), z.step)
                               : layout.RobotCol(z.seen, z.step);
    const Eigen::Vector2d res = WhitenedResidual(z);
    // Jacobians of the residual (z - h): -dh.
    const Eigen::Matrix<double, 2, 3> jx = -filters::MeasurementJacobianPose(p, x);
    Eigen::Matrix<double, 2, 3> jp = Eigen::Matrix<double, 2, 3>::Zero();
    jp.leftCols<2>() = -filters::MeasurementJacobianLandmark(p, x);
    rows->AddSquared(res,
                     {{layout.RobotCol(z.robot, z.step), z_w.asDiagonal() * jx}, {target_col, z_w.asDiagonal() * jp}});
  }
}

NormalEquations BatchSmoother::Equations(const Layout& layout, bool jacobians) const {
  NormalEquations rows(layout.cols, jacobians);
  BuildRows(layout, &rows);
  return rows;
}

void BatchSmoother::Apply(const Layout& layout, const Eigen::VectorXd& delta, double sign) {
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    for (int t = r == 0 ? 1 : 0; t <= Steps(static_cast<int>(r)); ++t) {
      Pose2& x = robots_[r].path[t];
      x = Pose2::FromVector(x.Vector() + sign * delta.segment<3>(layout.RobotCol(static_cast<int>(r), t)));
    }
  }
  for (auto& [id, chain] : chains_) {
    for (std::size_t i = 0; i < chain.states.size(); ++i) {
      const int col = layout.chain_col.at(id) + 3 * static_cast<int>(i);
      chain.states[i] = Pose2::FromVector(chain.states[i].Vector() + sign * delta.segment<3>(col));
    }
  }
  for (std::size_t r = 0; r < robots_.size() && estimate_calibration_; ++r) {
    robots_[r].correction += sign * delta.segment<3>(layout.CorrectionCol(static_cast<int>(r)));
  }
}

void BatchSmoother::SolveOnce() {
  const Layout layout = MakeLayout();
  Eigen::VectorXd last;  // the step taken, put back by subtracting it
  LeastSquares problem;
  problem.cols = layout.cols;
  problem.equations = [&](bool jacobians) { return Equations(layout, jacobians); };
  problem.step = [&](const Eigen::VectorXd& delta) {
    last = delta;
    Apply(layout, delta, 1.0);
  };
  problem.save = [] {};
  problem.restore = [&] { Apply(layout, last, -1.0); };
  problem.min_relative_decrease = relative_cost_tolerance_;
  Factorization solver;
  LevenbergMarquardt(problem, 30, 0.0, &solver);
}

Eigen::Matrix3d BatchSmoother::FirstPoseCovariance(int r) const {
  if (r < 1 || r >= static_cast<int>(robots_.size())) throw std::out_of_range("no robot placed by the data there");
  return PoseBlockCovariance(r, 0);
}

Eigen::Matrix3d BatchSmoother::PoseCovariance(int r) const {
  if (r < 0 || r >= static_cast<int>(robots_.size())) throw std::out_of_range("no such robot");
  if (r == 0 && robots_[0].path.size() == 1) return Eigen::Matrix3d::Zero();  // the known first pose
  return PoseBlockCovariance(r, -1);
}

Eigen::Matrix3d BatchSmoother::PoseBlockCovariance(int r, int t) const {
  const Layout layout = MakeLayout();
  const Factorization information(Equations(layout, true).Matrix());
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(layout.cols, 3);
  const int col = layout.RobotCol(r, t < 0 ? Steps(r) : t);
  e.block<3, 3>(col, 0).setIdentity();
  const Eigen::MatrixXd x = information.solve(e);
  const bool ok = information.info() == Eigen::Success && x.allFinite();
  return ok ? Eigen::Matrix3d(x.block<3, 3>(col, 0))
            : Eigen::Matrix3d::Constant(std::numeric_limits<double>::infinity());
}

std::vector<std::pair<Eigen::Vector2d, int>> BatchSmoother::Landmarks() const {
  std::vector<std::pair<Eigen::Vector2d, int>> out;
  for (const auto& [id, chain] : chains_) out.emplace_back(chain.states.back().Translation(), id);
  return out;
}

}  // namespace mrslam::robot_agent::smoother
