#include "robot_agent/smoother/keyframe_graph.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "common/angles.h"
#include "common/gaussian.h"
#include "robot_agent/filters/landmark_ekf.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/smoother/graph_factors.h"
#include "robot_agent/smoother/levenberg_marquardt.h"

namespace mrslam::robot_agent::smoother {
namespace {

using common::Pose2;
using common::WrapAngle;

}  // namespace

KeyframeGraph::KeyframeGraph(const AgentOptions& options, const Pose2& start)
    : dt_s_(options.dt_s),
      window_keyframes_(std::max(2, options.filter.smoother.window_keyframes)),
      max_iterations_(std::max(1, options.filter.smoother.max_iterations)),
      relinearize_threshold_(options.filter.smoother.relinearize_threshold),
      // (The newest keyframe a relinearization holds must still be in the window when it is applied.)
      relinearize_delay_steps_(std::clamp(options.filter.smoother.relinearize_delay_steps, 0, window_keyframes_ - 1)),
      huber_k_(options.filter.smoother.huber_k),
      gate_(common::ChiSquare2Quantile(options.filter.smoother.reading_gate_probability)),
      robot_var_(options.noise.robot_process_var),
      landmark_var_(options.noise.landmark_process_var),
      z_w_(ReadingWeights(options.sensors.lidar)) {
  Keyframe first;
  first.pose = start;
  first.fixed = true;
  window_.push_back(first);
  const auto& o = options.filter.smoother;
  const Eigen::Vector3d sd(o.speed_factor_sd, o.turn_factor_sd, o.turn_bias_sd_radps);
  prior_.vars = {{Var::kCorrection, 0}};
  prior_.x0 = {correction_};
  prior_.h = sd.cwiseProduct(sd).cwiseInverse().asDiagonal();
  prior_.g = Eigen::Vector3d::Zero();
  calibration_prior_ = prior_;
}

Pose2 KeyframeGraph::MoverIncrement(const MoverModel& model, int steps) const {
  Pose2 out;
  for (int i = 0; i < steps; ++i) out = common::UnicycleStep(out, model.v_mps, model.w_radps, dt_s_);
  return out;
}

Eigen::Matrix3d KeyframeGraph::MoverWhitening(const MoverModel& model, int steps) const {
  const std::vector<Pose2> increments(steps, MoverIncrement(model, 1));
  return Whitening(AccumulateCovariance(increments, landmark_var_));
}

void KeyframeGraph::AddMotion(const std::vector<Motion>& segments) {
  Settle();
  pending_.push_back(segments);
}

void KeyframeGraph::AddKeyframe(int step, const std::vector<Reading>& readings) {
  Settle();
  ApplyRelinearization(step);
  Keyframe kf;
  kf.step = step;
  kf.pose = common::Compose(window_.back().pose, OdometryIncrement(pending_, correction_));
  kf.has_odometry = true;
  kf.steps = std::move(pending_);
  pending_.clear();
  kf.odometry_whitening = Whitening(OdometryCovariance(kf.steps, correction_, robot_var_));
  for (const auto& z : readings) {
    if (std::isfinite(z.range_m) && std::isfinite(z.bearing_rad)) kf.readings.push_back({z, true});
  }
  window_.push_back(std::move(kf));
  while (static_cast<int>(window_.size()) > window_keyframes_) Marginalize();
}

double KeyframeGraph::PriorDrift() const {
  double drift = 0.0;
  for (std::size_t i = 0; i < prior_.vars.size(); ++i) {
    drift = std::max(drift, Difference(prior_.vars[i], prior_.x0[i]).cwiseAbs().maxCoeff());
  }
  return drift;
}

void KeyframeGraph::Relinearize() {
  if (relinearize_delay_steps_ == 0 || !movers_.empty()) {
    KeyframeGraph all = Whole();
    all.SolveWithGate();
    Adopt(std::move(all));
    return;
  }
  std::vector<Keyframe> history = std::move(history_);
  history_.clear();
  const std::size_t history_bytes = std::exchange(history_bytes_, 0);
  auto at = std::make_shared<const KeyframeGraph>(*this);
  history_ = std::move(history);
  history_bytes_ = history_bytes;
  StartRelinearization(std::move(at), history_.size(), window_.back().step + relinearize_delay_steps_);
}

std::shared_ptr<KeyframeGraph> KeyframeGraph::WholeToSolve(const KeyframeGraph& at, std::size_t history) const {
  auto whole = std::make_shared<KeyframeGraph>(at);
  whole->history_.assign(history_.begin(), history_.begin() + static_cast<std::ptrdiff_t>(history));
  whole->MakeWhole();
  return whole;
}

void KeyframeGraph::StartRelinearization(std::shared_ptr<const KeyframeGraph> at, std::size_t history, int apply_at) {
  Relinearization r;
  r.history = history;
  r.apply_at = apply_at;
  std::shared_ptr<KeyframeGraph> whole = WholeToSolve(*at, history);
  r.bytes = at->EstimatorBytes() + whole->EstimatorBytes();
  r.at = std::move(at);
  r.solved = std::async(std::launch::async, [whole] {
               whole->SolveWithGate();
               return whole;
             }).share();
  relinearizing_ = std::move(r);
}

void KeyframeGraph::ApplyRelinearization(int step) {
  if (!relinearizing_ || step < relinearizing_->apply_at) return;
  const Relinearization r = std::move(*relinearizing_);
  relinearizing_.reset();
  relinearize_due_ = false;  // the next solve decides again
  // (Taken from the shared result: a copy of this graph made meanwhile does not apply it again.)
  KeyframeGraph& solved = *r.solved.get();
  if (!r.stale && !solved.window_.empty() && FindKeyframe(solved.window_.back().step) != nullptr)
    Adopt(std::move(solved));
}

void KeyframeGraph::MarkRelinearizationStale(int from_step) {
  if (relinearizing_ && from_step <= relinearizing_->at->window_.back().step) relinearizing_->stale = true;
}

void KeyframeGraph::Adopt(KeyframeGraph solved) {
  const Keyframe& held = solved.window_.back();
  const Keyframe* here = FindKeyframe(held.step);  // in the window: the delay is below its length
  const Pose2 shift = common::Compose(held.pose, common::Inverse(here->pose));
  for (const Keyframe& kf : window_) {
    if (kf.step <= held.step) continue;
    solved.window_.push_back(kf);
    solved.window_.back().pose = common::Compose(shift, kf.pose);
  }
  TurnCovariances(shift, &solved);  // before the states it moves join it
  for (const auto& [track, p] : landmarks_) solved.landmarks_.emplace(track, common::TransformPoint(shift, p));
  for (const auto& [key, state] : movers_) solved.movers_.emplace(key, common::Compose(shift, state));
  for (const auto& [key, heading] : chain_starts_)
    solved.chain_starts_.emplace(key, WrapAngle(heading + shift.heading));
  solved.pending_ = pending_;
  solved.static_tracks_ = static_tracks_;
  solved.mover_models_ = mover_models_;
  solved.moving_tracks_ = moving_tracks_;
  solved.window_keyframes_ = window_keyframes_;
  solved.max_iterations_ = max_iterations_;
  solved.relinearize_due_ = false;
  // (The solve has started every landmark and mover state it holds.)
  const int leaving = static_cast<int>(solved.window_.size()) - window_keyframes_;
  if (leaving > 0) solved.MarginalizeOldest(leaving);
  *this = std::move(solved);
}

void KeyframeGraph::TurnCovariances(const Pose2& shift, KeyframeGraph* solved) const {
  const Eigen::Matrix3d turn = common::ComposeJacobianRight(shift, {});  // the shift's rotation
  const Eigen::Matrix2d point_turn = turn.topLeftCorner<2, 2>();
  solved->pose_correction_cov_ = pose_correction_cov_;
  solved->pose_correction_cov_.topRows<3>() = turn * solved->pose_correction_cov_.topRows<3>();
  solved->pose_correction_cov_.leftCols<3>() = solved->pose_correction_cov_.leftCols<3>() * turn.transpose();
  solved->landmark_cov_.clear();
  for (const auto& [track, cov] : landmark_cov_) {
    const bool moved = solved->landmarks_.count(track) == 0;
    solved->landmark_cov_.emplace(track, moved ? Eigen::Matrix2d(point_turn * cov * point_turn.transpose()) : cov);
  }
  solved->mover_cov_.clear();
  for (const auto& [key, cov] : mover_cov_) {
    const bool moved = solved->movers_.count(key) == 0;
    solved->mover_cov_.emplace(key, moved ? Eigen::Matrix3d(turn * cov * turn.transpose()) : cov);
  }
}

void KeyframeGraph::Relabel(int from_step, const std::map<std::uint32_t, std::uint32_t>& from_to) {
  Settle();
  MarkRelinearizationStale(from_step);
  for (auto& kf : window_) {
    if (kf.step < from_step) continue;
    for (auto& r : kf.readings) {
      const auto it = from_to.find(r.z.track);
      if (it != from_to.end()) {
        r.z.track = it->second;
        r.inlier = true;
      }
    }
  }
}

void KeyframeGraph::CutAndMove(int from_step, const Pose2& correction) {
  Settle();
  MarkRelinearizationStale(from_step);
  bool cut = false;
  for (auto& kf : window_) {
    if (kf.step < from_step || kf.fixed) continue;
    if (!cut) {
      kf.has_odometry = false;
      kf.odometry_cut = true;
      cut = true;
    }
    kf.pose = common::Compose(correction, kf.pose);
    for (auto& r : kf.readings) r.inlier = true;
  }
}

Eigen::VectorXd KeyframeGraph::Value(const Var& v) const {
  switch (v.kind) {
    case Var::kPose:
      return FindKeyframe(static_cast<int>(v.key))->pose.Vector();
    case Var::kLandmark:
      return landmarks_.at(static_cast<std::uint32_t>(v.key));
    case Var::kMover:
      return movers_.at(v.key).Vector();
    case Var::kCorrection:
      return correction_;
  }
  return {};
}

void KeyframeGraph::SetValue(const Var& v, const Eigen::VectorXd& value) {
  switch (v.kind) {
    case Var::kPose:
      FindKeyframe(static_cast<int>(v.key))->pose = Pose2::FromVector(value);
      return;
    case Var::kLandmark:
      landmarks_[static_cast<std::uint32_t>(v.key)] = value;
      return;
    case Var::kMover:
      movers_[v.key] = Pose2::FromVector(value);
      return;
    case Var::kCorrection:
      correction_ = value;
      return;
  }
}

Eigen::VectorXd KeyframeGraph::Difference(const Var& v, const Eigen::VectorXd& x0) const {
  Eigen::VectorXd d = Value(v) - x0;
  if (v.kind == Var::kPose || v.kind == Var::kMover) d(2) = WrapAngle(d(2));
  return d;
}

const KeyframeGraph::Keyframe* KeyframeGraph::FindKeyframe(int step) const {
  // The window's steps increase.
  const auto it =
      std::lower_bound(window_.begin(), window_.end(), step, [](const Keyframe& kf, int s) { return kf.step < s; });
  return it != window_.end() && it->step == step ? &*it : nullptr;
}

KeyframeGraph::Keyframe* KeyframeGraph::FindKeyframe(int step) {
  return const_cast<Keyframe*>(std::as_const(*this).FindKeyframe(step));
}

std::vector<KeyframeGraph::Var> KeyframeGraph::Variables(int oldest) const {
  std::set<Var> vars(prior_.vars.begin(), prior_.vars.end());
  vars.insert({Var::kCorrection, 0});
  const std::size_t leaving = std::min<std::size_t>(oldest == 0 ? 1 : oldest, window_.size());
  const std::size_t kfs = oldest == 0 ? window_.size() : std::min<std::size_t>(leaving + 1, window_.size());
  for (std::size_t i = 0; i < kfs; ++i) {
    const Keyframe& kf = window_[i];
    if (!kf.fixed) vars.insert({Var::kPose, kf.step});
    if (oldest > 0 && i >= leaving) continue;
    for (const auto& r : kf.readings) {
      if (Active(r) && landmarks_.count(r.z.track) > 0) vars.insert({Var::kLandmark, r.z.track});
    }
  }
  // Mover states: all (oldest > 0: those at the leaving keyframes and each chain's next one).
  const int last_step = window_[leaving - 1].step;
  std::vector<Var> eliminated;
  for (std::size_t i = 0; i < leaving; ++i) {
    if (!window_[i].fixed) eliminated.push_back({Var::kPose, window_[i].step});
  }
  for (const auto& [key, state] : movers_) {
    if (MoverStep(key) <= last_step) eliminated.push_back({Var::kMover, key});
    if (oldest == 0) vars.insert({Var::kMover, key});
  }
  if (oldest > 0) {
    for (const Var& v : eliminated) {
      if (v.kind != Var::kMover) continue;
      const auto next = movers_.upper_bound(MoverKey(MoverTrack(v.key), last_step));
      if (next != movers_.end() && MoverTrack(next->first) == MoverTrack(v.key))
        vars.insert({Var::kMover, next->first});
    }
  }
  // The leaving keyframes' poses and mover states first: a marginalization eliminates them.
  for (const Var& v : eliminated) vars.erase(v);
  std::vector<Var> out = eliminated;
  out.insert(out.end(), vars.begin(), vars.end());
  return out;
}

KeyframeGraph::Layout KeyframeGraph::MakeLayout(const std::vector<Var>& vars) const {
  Layout layout;
  for (const Var& v : vars) {
    layout.col[v] = layout.cols;
    layout.cols += Dim(v);
  }
  return layout;
}

// Every moving track's chain spans the keyframes from its first state (or reading) to its last
// reading; missing states are predicted by its model from the one before, a new chain starts at
// its first reading.
void KeyframeGraph::StartMovers() {
  for (const std::uint32_t track : moving_tracks_) {
    const MoverModel& model = mover_models_.at(track);
    int last_reading = -1;
    for (const auto& kf : window_) {
      for (const auto& r : kf.readings) {
        if (r.inlier && r.z.track == track) last_reading = kf.step;
      }
    }
    if (last_reading < 0) continue;
    const Pose2* previous = nullptr;
    int previous_step = 0;
    for (const auto& kf : window_) {
      if (kf.step > last_reading) break;
      const std::int64_t key = MoverKey(track, kf.step);
      if (movers_.count(key) == 0) {
        if (previous != nullptr) {
          movers_[key] = common::Compose(*previous, MoverIncrement(model, kf.step - previous_step));
        } else {
          bool started = false;
          for (const auto& r : kf.readings) {
            if (started || !r.inlier || r.z.track != track) continue;
            const Eigen::Vector2d p = common::PointFromRangeBearing(kf.pose, {r.z.range_m, r.z.bearing_rad});
            movers_[key] = Pose2{p.x(), p.y(), model.start_heading};
            chain_starts_[key] = model.start_heading;
            started = true;
          }
          if (!started) continue;
        }
      }
      previous = &movers_.at(key);
      previous_step = kf.step;
    }
  }
}

double KeyframeGraph::TrialCost(std::uint32_t track, double v_mps, double w_radps) const {
  KeyframeGraph trial = *this;
  trial.history_.clear();  // not needed to solve the window
  trial.relinearizing_.reset();
  auto& model = trial.mover_models_.at(track);
  model.v_mps = v_mps;
  model.w_radps = w_radps;
  for (auto& kf : trial.window_) {
    for (auto& r : kf.readings) r.inlier = true;
  }
  trial.max_iterations_ = kTrialIterations;
  return trial.SolveOnce();
}

int KeyframeGraph::ChainStates(std::uint32_t track) const {
  const auto first = movers_.lower_bound(MoverKey(track, 0));
  const auto end = movers_.lower_bound(MoverKey(track + 1, 0));
  return static_cast<int>(std::distance(first, end));
}

void KeyframeGraph::DropStoppedChains() {
  const std::set<Var> held(prior_.vars.begin(), prior_.vars.end());
  for (auto it = movers_.begin(); it != movers_.end();) {
    if (moving_tracks_.count(MoverTrack(it->first)) == 0 && held.count({Var::kMover, it->first}) == 0) {
      chain_starts_.erase(it->first);
      it = movers_.erase(it);
    } else {
      ++it;
    }
  }
}

void KeyframeGraph::StartLandmarks() {
  for (const auto& kf : window_) {
    for (const auto& r : kf.readings) {
      if (!Active(r) || landmarks_.count(r.z.track) > 0) continue;
      landmarks_[r.z.track] = common::PointFromRangeBearing(kf.pose, {r.z.range_m, r.z.bearing_rad});
    }
  }
}

void KeyframeGraph::AddOdometryRows(const Layout& layout, const Keyframe& previous, const Keyframe& kf,
                                    Rows* rows) const {
  const OdometryFactor f = OdometryResidual(previous.pose, kf.pose, kf.odometry.At(kf.steps, correction_),
                                            kf.odometry_whitening, rows->jacobians);
  rows->cost += f.residual.squaredNorm();
  if (!rows->jacobians) return;
  const int c_col = layout.Col({Var::kCorrection, 0});
  rows->Add(f.residual, {{previous.fixed ? -1 : layout.Col({Var::kPose, previous.step}), f.d_a},
                         {layout.Col({Var::kPose, kf.step}), f.d_b},
                         {c_col, f.d_correction}});
}

void KeyframeGraph::AddReadingRows(const Layout& layout, const Keyframe& kf, Rows* rows) const {
  const int x_col = kf.fixed ? -1 : layout.Col({Var::kPose, kf.step});
  for (const auto& stored : kf.readings) {
    const bool mover = MoverReading(stored, kf.step);
    if (!Active(stored) && !mover) continue;
    const Var target =
        mover ? Var{Var::kMover, MoverKey(stored.z.track, kf.step)} : Var{Var::kLandmark, stored.z.track};
    const int p_col = layout.Col(target);
    if (p_col < 0) continue;
    const Eigen::Vector2d p = mover ? movers_.at(target.key).Translation() : landmarks_.at(stored.z.track);
    const ReadingFactor f =
        RobustReading(kf.pose, p, stored.z.range_m, stored.z.bearing_rad, z_w_, huber_k_, rows->jacobians);
    rows->cost += f.cost;
    if (!rows->jacobians) continue;
    Rows::Block jp = Rows::Block::Zero(2, Dim(target));
    jp.leftCols<2>() = f.d_point;
    rows->Add(f.residual, {{x_col, f.d_pose}, {p_col, jp}});
  }
}

void KeyframeGraph::AddMoverRows(const Layout& layout, std::uint32_t track, int from_step, int to_step,
                                 Rows* rows) const {
  const auto model = mover_models_.find(track);
  if (model == mover_models_.end()) return;
  const Var a{Var::kMover, MoverKey(track, from_step)}, b{Var::kMover, MoverKey(track, to_step)};
  const BetweenJacobians between = BetweenWithJacobians(movers_.at(a.key), movers_.at(b.key));
  Eigen::Vector3d e = between.value - MoverIncrement(model->second, to_step - from_step).Vector();
  e(2) = WrapAngle(e(2));
  const Eigen::Matrix3d w = MoverWhitening(model->second, to_step - from_step);
  const Eigen::Vector3d r = w * e;
  rows->AddSquared(r, {{layout.Col(a), w * between.ja}, {layout.Col(b), w * between.jb}});
}

void KeyframeGraph::BuildRows(const Layout& layout, int oldest, Rows* rows) const {
  const std::size_t leaving = oldest == 0 ? window_.size() : std::min<std::size_t>(oldest, window_.size());
  const std::size_t last = std::min(leaving, window_.size() - 1);
  for (std::size_t i = 0; i <= last; ++i) {
    if (i > 0 && window_[i].has_odometry) AddOdometryRows(layout, window_[i - 1], window_[i], rows);
    if (i < leaving) AddReadingRows(layout, window_[i], rows);
  }
  const int last_step = window_[leaving - 1].step;
  std::uint32_t track = 0;
  int previous = -1;
  for (const auto& [key, state] : movers_) {
    const bool same_chain = MoverTrack(key) == track && previous >= 0;
    if (same_chain && previous <= last_step) AddMoverRows(layout, track, previous, MoverStep(key), rows);
    track = MoverTrack(key);
    previous = MoverStep(key);
    if (chain_starts_.count(key) > 0 && previous <= last_step) {
      // The weak prior on the heading the chain started with.
      Rows::Block j = Rows::Block::Zero(1, 3);
      j(0, 2) = 1e-3;
      const Rows::Residual r = Rows::Residual::Constant(1, 1e-3 * WrapAngle(state.heading - chain_starts_.at(key)));
      rows->AddSquared(r, {{layout.Col({Var::kMover, key}), j}});
    }
  }
}

void KeyframeGraph::AddPrior(const Layout& layout, Rows* rows) const {
  const int n = static_cast<int>(prior_.g.size());
  Eigen::VectorXd d(n);
  std::vector<int> cols;
  for (std::size_t v = 0, o = 0; v < prior_.vars.size(); o += Dim(prior_.vars[v]), ++v) {
    d.segment(static_cast<int>(o), Dim(prior_.vars[v])) = Difference(prior_.vars[v], prior_.x0[v]);
    const int c = layout.Col(prior_.vars[v]);
    for (int k = 0; k < Dim(prior_.vars[v]); ++k) cols.push_back(c < 0 ? -1 : c + k);
  }
  const Eigen::VectorXd hd = prior_.h * d;
  rows->cost += d.dot(hd) + 2.0 * prior_.g.dot(d);
  if (!rows->jacobians) return;
  for (int i = 0; i < n; ++i) {
    if (cols[i] < 0) continue;
    rows->g(cols[i]) += hd(i) + prior_.g(i);
    for (int j = 0; j < n; ++j) {
      if (cols[j] >= 0 && cols[j] <= cols[i] && prior_.h(i, j) != 0.0)
        rows->h.emplace_back(cols[i], cols[j], prior_.h(i, j));
    }
  }
}

// The normal equations (or, without jacobians, only the cost) of every factor of the window
// and the prior at the current values.
KeyframeGraph::Rows KeyframeGraph::Equations(const Layout& layout, int oldest, bool jacobians) const {
  Rows rows(layout.cols, jacobians);
  BuildRows(layout, oldest, &rows);
  AddPrior(layout, &rows);
  return rows;
}

// One Levenberg-Marquardt solve over the window; returns the final cost. Keeps the last
// iteration's factorization for the covariances when its damping is negligible.
double KeyframeGraph::SolveOnce() {
  StartLandmarks();
  StartMovers();
  const std::vector<Var> vars = Variables(0);
  const Layout layout = MakeLayout(vars);
  std::vector<Eigen::VectorXd> saved;  // the values before a step, in the order of vars
  LeastSquares problem;
  problem.cols = layout.cols;
  problem.equations = [&](bool jacobians) { return Equations(layout, 0, jacobians); };
  problem.step = [&](const Eigen::VectorXd& delta) {
    for (const Var& v : vars) SetValue(v, Value(v) + delta.segment(layout.Col(v), Dim(v)));
  };
  problem.save = [&] {
    saved.clear();
    for (const Var& v : vars) saved.push_back(Value(v));
  };
  problem.restore = [&] {
    for (std::size_t i = 0; i < vars.size(); ++i) SetValue(vars[i], saved[i]);
  };
  auto solver = std::make_shared<Factorization>();
  const LmResult result = LevenbergMarquardt(problem, max_iterations_, kRidge, solver.get());
  information_ = result.InformationUsable() ? std::move(solver) : nullptr;
  information_vars_ = vars;
  return result.cost;
}

bool KeyframeGraph::UpdateInliers() {
  bool changed = false;
  for (auto& kf : window_) {
    for (auto& r : kf.readings) {
      const auto mover = movers_.find(MoverKey(r.z.track, kf.step));
      const auto it = landmarks_.find(r.z.track);
      Eigen::Vector2d p;
      if (moving_tracks_.count(r.z.track) > 0 && mover != movers_.end()) {
        p = mover->second.Translation();
      } else if (it != landmarks_.end()) {
        p = it->second;
      } else {
        continue;
      }
      const bool inlier = WhitenedReading(kf.pose, p, r.z.range_m, r.z.bearing_rad, z_w_).squaredNorm() <= gate_;
      changed = changed || inlier != r.inlier;
      r.inlier = inlier;
    }
  }
  if (changed) information_ = nullptr;
  return changed;
}

void KeyframeGraph::Io(common::Archive& ar) {
  IoState(ar);
  IoRelinearization(ar);
}

void KeyframeGraph::IoState(common::Archive& ar) {
  ar(window_, history_, pending_, landmarks_, static_tracks_, mover_models_, moving_tracks_, movers_, chain_starts_,
     correction_, prior_, calibration_prior_, pose_correction_cov_, landmark_cov_, mover_cov_, relinearize_due_);
  if (!ar.loading()) return;
  if (window_.empty()) throw common::ArchiveError("archive: a keyframe graph without keyframes");
  information_ = nullptr;  // a factorization of the last solve: that solve's own
  information_vars_.clear();
  history_bytes_ = 0;
  for (const Keyframe& kf : history_) history_bytes_ += HeldBytes(kf);
}

// A relinearization under way: the graph it started from (without its history) and when it is
// applied; on reading, it is started again from the same graph, so it gives the same result.
void KeyframeGraph::IoRelinearization(common::Archive& ar) {
  bool under_way = relinearizing_.has_value();
  ar(under_way);
  if (!under_way) {
    relinearizing_.reset();
    return;
  }
  std::uint64_t history = 0;
  int apply_at = 0;
  bool stale = false;
  auto at = std::make_shared<KeyframeGraph>(ar.loading() ? *this : *relinearizing_->at);
  at->relinearizing_.reset();
  if (!ar.loading()) {
    history = relinearizing_->history;
    apply_at = relinearizing_->apply_at;
    stale = relinearizing_->stale;
  }
  ar(history, apply_at, stale);
  at->IoState(ar);
  if (!ar.loading()) return;
  if (history > history_.size()) throw common::ArchiveError("archive: a relinearization beyond the history");
  StartRelinearization(std::move(at), history, apply_at);
  relinearizing_->stale = stale;
}

std::size_t KeyframeGraph::KeyframeBytes(int steps, int segments, int readings) {
  return sizeof(Keyframe) + static_cast<std::size_t>(steps) * sizeof(std::vector<Motion>) +
         static_cast<std::size_t>(segments) * sizeof(Motion) +
         static_cast<std::size_t>(readings) * sizeof(StoredReading);
}

std::size_t KeyframeGraph::MotionBytes(const std::vector<std::vector<Motion>>& steps) {
  std::size_t bytes = filters::ElementBytes(steps);
  for (const auto& segments : steps) bytes += filters::ElementBytes(segments);
  return bytes;
}

std::size_t KeyframeGraph::HeldBytes(const Keyframe& kf) {
  return sizeof(Keyframe) + MotionBytes(kf.steps) + filters::ElementBytes(kf.readings);
}

std::size_t KeyframeGraph::EstimatorBytes() const {
  const auto prior_bytes = [](const Prior& p) {
    std::size_t bytes = filters::ElementBytes(p.vars) + filters::ElementBytes(p.x0) +
                        sizeof(double) * static_cast<std::size_t>(p.h.size() + p.g.size());
    for (const auto& x0 : p.x0) bytes += sizeof(double) * static_cast<std::size_t>(x0.size());
    return bytes;
  };
  std::size_t bytes = MotionBytes(pending_) + filters::ElementBytes(landmarks_) +
                      filters::ElementBytes(static_tracks_) + filters::ElementBytes(mover_models_) +
                      filters::ElementBytes(moving_tracks_) + filters::ElementBytes(movers_) +
                      filters::ElementBytes(chain_starts_) + prior_bytes(prior_) + prior_bytes(calibration_prior_) +
                      filters::ElementBytes(landmark_cov_) + filters::ElementBytes(mover_cov_);
  for (const Keyframe& kf : window_) bytes += HeldBytes(kf);
  if (relinearizing_) bytes += relinearizing_->bytes;
  return bytes + history_bytes_;
}

void KeyframeGraph::Solve() {
  Settle();
  SolveWithGate();
  ComputeCovariances();
  relinearize_due_ = relinearize_threshold_ > 0.0 && !history_.empty() && PriorDrift() > relinearize_threshold_;
}

void KeyframeGraph::Settle() {
  if (!relinearize_due_ || relinearizing_) return;
  relinearize_due_ = false;
  Relinearize();
}

void KeyframeGraph::SolveWithGate() {
  SolveOnce();
  for (int round = 0; round < 3 && UpdateInliers(); ++round) SolveOnce();
}

void KeyframeGraph::Marginalize() {
  StartLandmarks();
  StartMovers();
  MarginalizeOldest(1);
}

void KeyframeGraph::MarginalizeOldest(int count) {
  const std::vector<Var> vars = Variables(count);
  const Layout layout = MakeLayout(vars);
  const Rows rows = Equations(layout, count, true);
  const Eigen::SparseMatrix<double> h = rows.Matrix();  // the lower triangle
  const Eigen::VectorXd& g = rows.g;
  const int last_step = window_[count - 1].step;
  // The leaving poses' and mover states' columns come first.
  std::size_t eliminated = 0;
  int m = 0;
  const auto leaves = [&](const Var& v) {
    return (v.kind == Var::kPose && v.key <= last_step) || (v.kind == Var::kMover && MoverStep(v.key) <= last_step);
  };
  while (eliminated < vars.size() && leaves(vars[eliminated])) m += Dim(vars[eliminated++]);
  const int n = layout.cols - m;
  Prior next;
  next.vars.assign(vars.begin() + static_cast<std::ptrdiff_t>(eliminated), vars.end());
  for (const Var& v : next.vars) next.x0.push_back(Value(v));
  next.h = Eigen::MatrixXd(h.bottomRightCorner(n, n)).selfadjointView<Eigen::Lower>();
  next.g = g.tail(n);
  if (m > 0) {
    // (A state without information left, e.g. of a chain that ended, is dropped.)
    Eigen::SparseMatrix<double> hmm = h.topLeftCorner(m, m);
    for (int c = 0; c < m; ++c) hmm.coeffRef(c, c) += 1e-9;
    const Eigen::SparseMatrix<double> hrm = h.bottomLeftCorner(n, m);
    const Factorization elimination(hmm);
    next.h -= hrm * elimination.solve(Eigen::MatrixXd(hrm.transpose()));
    next.g -= hrm * elimination.solve(g.head(m));
  }
  next.h = 0.5 * (next.h + next.h.transpose());
  prior_ = std::move(next);
  for (std::size_t i = 0; i < eliminated; ++i) {
    if (vars[i].kind != Var::kMover) continue;
    movers_.erase(vars[i].key);
    chain_starts_.erase(vars[i].key);
  }
  for (int i = 0; i < count; ++i) {
    history_bytes_ += HeldBytes(window_.front());
    history_.push_back(std::move(window_.front()));
    window_.pop_front();
  }
  window_.front().has_odometry = false;
}

// The variables whose marginals are computed: the newest pose (unless the known start), the
// correction, each moving landmark's newest state, and the static landmarks read at the newest
// keyframe or without one yet (the others keep theirs: information only accrues, so a kept
// covariance errs on the large side).
std::vector<KeyframeGraph::Var> KeyframeGraph::CovarianceTargets(const std::vector<Var>& vars) const {
  std::vector<Var> wanted;
  if (!window_.back().fixed) wanted.push_back({Var::kPose, window_.back().step});
  wanted.push_back({Var::kCorrection, 0});
  std::set<std::uint32_t> read;
  for (const auto& r : window_.back().readings) read.insert(r.z.track);
  std::map<std::uint32_t, Var> newest_mover;
  for (const Var& v : vars) {
    const auto track = static_cast<std::uint32_t>(v.key);
    if (v.kind == Var::kLandmark && (read.count(track) > 0 || landmark_cov_.count(track) == 0)) wanted.push_back(v);
    if (v.kind == Var::kMover) newest_mover[MoverTrack(v.key)] = v;  // keys ascend by step
  }
  for (const auto& [track, v] : newest_mover) wanted.push_back(v);
  return wanted;
}

// The factorized information matrix at the solution: the last solve's, or afresh.
std::shared_ptr<const Factorization> KeyframeGraph::Information(const std::vector<Var>& vars,
                                                                const Layout& layout) const {
  if (information_ != nullptr && information_vars_ == vars) return information_;
  Eigen::SparseMatrix<double> identity(layout.cols, layout.cols);
  identity.setIdentity();
  return std::make_shared<const Factorization>(Equations(layout, 0, true).Matrix() + kRidge * identity);
}

void KeyframeGraph::ComputeCovariances() {
  const std::vector<Var> vars = Variables(0);
  const Layout layout = MakeLayout(vars);
  const std::shared_ptr<const Factorization> factorization = Information(vars, layout);
  const Factorization& information = *factorization;
  const std::vector<Var> wanted = CovarianceTargets(vars);
  std::map<Var, int> offset;  // of each wanted variable's columns in the right-hand side
  int rhs = 0;
  for (const Var& v : wanted) {
    offset[v] = rhs;
    rhs += Dim(v);
  }
  // With P H P^T = L D L^T, H^-1 = P^T L^-T D^-1 L^-1 P, so the block of H^-1 at (a, b) is
  // Y_a^T D^-1 Y_b with Y = L^-1 P E, E the identity's columns of the wanted variables: a
  // forward substitution only, which skips the columns of L above the first nonzero of the
  // right-hand side (the wanted variables tend to be eliminated late).
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(layout.cols, rhs);
  for (const Var& v : wanted) y.block(layout.Col(v), offset[v], Dim(v), Dim(v)).setIdentity();
  y = information.permutationP() * y;
  information.matrixL().solveInPlace(y);
  const Eigen::VectorXd d_inverse = information.vectorD().cwiseInverse();
  std::map<std::uint32_t, Eigen::Matrix2d> kept;
  for (const Var& v : vars) {
    const auto it = landmark_cov_.find(static_cast<std::uint32_t>(v.key));
    if (v.kind == Var::kLandmark && it != landmark_cov_.end()) kept.insert(*it);
  }
  landmark_cov_ = std::move(kept);
  mover_cov_.clear();
  if (information.info() != Eigen::Success || !y.allFinite() || !d_inverse.allFinite()) return;
  auto block = [&](const Var& a, const Var& b) -> Eigen::MatrixXd {
    return y.middleCols(offset[a], Dim(a)).transpose() * d_inverse.asDiagonal() * y.middleCols(offset[b], Dim(b));
  };
  const Var pose{Var::kPose, window_.back().step}, correction{Var::kCorrection, 0};
  pose_correction_cov_.setZero();
  pose_correction_cov_.bottomRightCorner<3, 3>() = block(correction, correction);
  if (offset.count(pose) > 0) {
    pose_correction_cov_.topLeftCorner<3, 3>() = block(pose, pose);
    pose_correction_cov_.topRightCorner<3, 3>() = block(pose, correction);
    pose_correction_cov_.bottomLeftCorner<3, 3>() = block(correction, pose);
  }
  for (const Var& v : wanted) {
    if (v.kind == Var::kLandmark) landmark_cov_[static_cast<std::uint32_t>(v.key)] = block(v, v);
    if (v.kind == Var::kMover) mover_cov_[v.key] = block(v, v);
  }
}

Pose2 KeyframeGraph::Pose() const {
  return common::Compose(window_.back().pose, OdometryIncrement(pending_, correction_));
}

std::vector<Pose2> KeyframeGraph::KeyframePoses() const {
  std::vector<Pose2> out;
  out.reserve(history_.size() + window_.size());
  for (const Keyframe& k : history_) out.push_back(k.pose);
  for (const Keyframe& k : window_) out.push_back(k.pose);
  return out;
}

Eigen::Matrix3d KeyframeGraph::PoseCovariance() const {
  const Pose2& kf = window_.back().pose;
  const OdometryIncrementJacobians increment = OdometryIncrementWithJacobian(pending_, correction_);
  const Pose2& delta = increment.delta;
  Eigen::Matrix<double, 3, 6> j;
  j.leftCols<3>() = common::ComposeJacobianLeft(kf, delta);
  j.rightCols<3>() = common::ComposeJacobianRight(kf, delta) * increment.d_correction;
  const Eigen::Matrix3d rot = common::ComposeJacobianRight(kf, delta);
  Eigen::Matrix3d cov = j * pose_correction_cov_ * j.transpose();
  if (!pending_.empty()) cov += rot * OdometryCovariance(pending_, correction_, robot_var_) * rot.transpose();
  return 0.5 * (cov + cov.transpose());
}

std::vector<KeyframeGraph::Landmark> KeyframeGraph::Landmarks() const {
  std::vector<Landmark> out;
  for (const auto& [track, cov] : landmark_cov_) {
    if (static_tracks_.count(track) > 0) out.push_back({track, landmarks_.at(track), cov});
  }
  return out;
}

std::vector<KeyframeGraph::Mover> KeyframeGraph::Movers() const {
  std::vector<Mover> out;
  for (const auto& [key, cov] : mover_cov_) {
    if (moving_tracks_.count(MoverTrack(key)) > 0)
      out.push_back({MoverTrack(key), movers_.at(key), cov, MoverStep(key)});
  }
  return out;
}

KeyframeGraph::Prediction KeyframeGraph::PredictMover(const Mover& mover, int step) const {
  const int n = std::max(0, step - mover.step);
  const MoverModel& model = mover_models_.at(mover.track);
  const Pose2 delta = MoverIncrement(model, n);
  const Eigen::Matrix3d f = common::ComposeJacobianLeft(mover.state, delta);
  const Eigen::Matrix3d rot = common::ComposeJacobianRight(mover.state, delta);
  Eigen::Matrix3d cov = f * mover.covariance * f.transpose();
  if (n > 0)
    cov += rot * AccumulateCovariance(std::vector<Pose2>(n, MoverIncrement(model, 1)), landmark_var_) * rot.transpose();
  return {common::Compose(mover.state, delta), 0.5 * (cov + cov.transpose())};
}

std::vector<std::pair<int, Pose2>> KeyframeGraph::Path() const {
  std::vector<std::pair<int, Pose2>> out;
  out.reserve(history_.size() + window_.size());
  for (const auto& kf : history_) out.emplace_back(kf.step, kf.pose);
  for (const auto& kf : window_) out.emplace_back(kf.step, kf.pose);
  return out;
}

KeyframeGraph KeyframeGraph::Whole() const {
  KeyframeGraph all(*this);
  all.MakeWhole();
  return all;
}

void KeyframeGraph::MakeWhole() {
  window_.insert(window_.begin(), std::make_move_iterator(history_.begin()), std::make_move_iterator(history_.end()));
  history_.clear();
  history_bytes_ = 0;
  for (auto& kf : window_) kf.has_odometry = !kf.fixed && !kf.odometry_cut;
  prior_ = calibration_prior_;
  window_keyframes_ = std::numeric_limits<int>::max();
  max_iterations_ = 100;
  relinearizing_.reset();
}

std::vector<std::pair<int, Pose2>> KeyframeGraph::SmoothAll() const {
  KeyframeGraph all = Whole();
  all.SolveWithGate();
  return all.Path();
}

std::vector<std::pair<KeyframeGraph::Reading, bool>> KeyframeGraph::NewestReadings() const {
  std::vector<std::pair<Reading, bool>> out;
  for (const auto& r : window_.back().readings) out.emplace_back(r.z, r.inlier);
  return out;
}

}  // namespace mrslam::robot_agent::smoother
