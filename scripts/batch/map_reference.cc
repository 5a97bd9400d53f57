#include "scripts/batch/map_reference.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "common/angles.h"
#include "robot_agent/core/slam_filter.h"

namespace mrslam::batch {
namespace {

using common::Pose2;
using common::WrapAngle;

// A variance used as a whitening divisor: zero (a noise-free model) becomes a stiff tiny one.
double Sd(double var) { return std::sqrt(std::max(var, 1e-12)); }

// Appends the rows of one whitened residual block: r (size n) and its Jacobian blocks
// (n x 3 each) for the variables at the given column offsets (-1: a known quantity, no column).
struct Rows {
  std::vector<Eigen::Triplet<double>> jacobian;
  std::vector<double> residual;

  void Add(const Eigen::VectorXd& r, const std::vector<std::pair<int, Eigen::MatrixXd>>& blocks) {
    const int row = static_cast<int>(residual.size());
    for (int i = 0; i < r.size(); ++i) residual.push_back(r(i));
    for (const auto& [col, j] : blocks) {
      if (col < 0) continue;
      for (int i = 0; i < j.rows(); ++i) {
        for (int c = 0; c < j.cols(); ++c) {
          if (j(i, c) != 0.0) jacobian.emplace_back(row + i, col + c, j(i, c));
        }
      }
    }
  }
};

// a - b on poses, heading wrapped.
Eigen::Vector3d Minus(const Pose2& a, const Pose2& b) {
  return {a.x - b.x, a.y - b.y, WrapAngle(a.heading - b.heading)};
}

// Jacobian of g at x by central differences (g: Pose2 -> Pose2, differences as Minus).
template <typename G>
Eigen::Matrix3d NumericJacobian(const G& g, const Pose2& x) {
  Eigen::Matrix3d j;
  constexpr double kH = 1e-6;
  for (int c = 0; c < 3; ++c) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d(c) = kH;
    const Pose2 plus = g(Pose2::FromVector(x.Vector() + d)), minus = g(Pose2::FromVector(x.Vector() - d));
    j.col(c) = Minus(plus, minus) / (2.0 * kH);
  }
  return j;
}

}  // namespace

MapReference::MapReference(const common::ScenarioOptions& options, int robot_index)
    : dt_s_(options.run.dt_s),
      robot_var_(options.noise.robot_process_var),
      landmark_var_(options.noise.landmark_process_var),
      var_r_(options.sensors.lidar.range_noise_sd_m * options.sensors.lidar.range_noise_sd_m),
      var_b_(options.sensors.lidar.bearing_noise_sd_rad * options.sensors.lidar.bearing_noise_sd_rad) {
  for (const auto& l : options.landmarks) {
    Kinematics k;
    if (l.motion.model == common::LandmarkMotionModel::kUnicycle) {
      k = {false, l.motion.v_mps, l.motion.w_radps};
    } else if (l.motion.model != common::LandmarkMotionModel::kStatic) {
      throw std::invalid_argument("the reference knows static and unicycle landmarks only (landmark " +
                                  std::to_string(l.id) + ")");
    }
    kinematics_[l.id] = k;
  }
  if (options.landmark_field.enabled) {
    throw std::invalid_argument("the reference knows listed landmarks only, not a landmark_field");
  }
  path_.push_back(robot_agent::InitialPoseInOwnFrame(options.robots.at(robot_index)));
}

Pose2 MapReference::StepRobot(const Pose2& x, int t) const {
  Pose2 out = x;
  for (const auto& s : odometry_[t - 1]) out = common::UnicycleStep(out, s.v_mps, s.w_radps, s.dt_s);
  return out;
}

Pose2 MapReference::StepLandmark(const Pose2& l, const Kinematics& k) const {
  return k.is_static ? l : common::UnicycleStep(l, k.v_mps, k.w_radps, dt_s_);
}

void MapReference::Process(const common::SensorStep& step) {
  odometry_.push_back(step.odometry.segments);
  const int t = static_cast<int>(path_.size());
  path_.push_back(StepRobot(path_.back(), t));
  for (auto& [id, chain] : chains_) chain.states.push_back(StepLandmark(chain.states.back(), chain.kinematics));
  for (const auto& d : step.lidar.landmarks) {
    if (d.landmark_id < 0) throw std::invalid_argument("the reference needs detections with identities");
    const auto known = kinematics_.find(d.landmark_id);
    if (known == kinematics_.end() || !std::isfinite(d.range_m) || !std::isfinite(d.bearing_rad)) continue;
    readings_.push_back({t, d.landmark_id, d.range_m, d.bearing_rad});
    const Eigen::Vector2d point = common::PointFromRangeBearing(path_.back(), {d.range_m, d.bearing_rad});
    auto [it, created] = chains_.try_emplace(d.landmark_id);
    Chain& chain = it->second;
    if (created) {
      chain.first_step = t;
      chain.kinematics = known->second;
      chain.states.push_back({point.x(), point.y(), 0.0});
    } else if (chain.sightings == 1 && !chain.kinematics.is_static) {
      // Second sighting: the heading from the displacement since the first (the chord of the
      // arc turns by w dt / 2 per step less than the heading at its end), then the chain again.
      const int steps = t - chain.first_step;
      const Pose2& first = chain.states.front();
      if (steps > 0) {
        const double chord = std::atan2(point.y() - first.y, point.x() - first.x);
        Pose2 l{first.x, first.y, WrapAngle(chord - 0.5 * chain.kinematics.w_radps * dt_s_ * (steps + 1))};
        for (auto& state : chain.states) {
          state = l;
          l = StepLandmark(l, chain.kinematics);
        }
      }
    }
    ++chain.sightings;
  }
  Solve();
}

void MapReference::Solve() {
  // Columns: robot poses 1..T, then every chain's states in id order.
  const int steps = static_cast<int>(path_.size()) - 1;
  std::map<int, int> chain_col;
  int cols = 3 * steps;
  for (const auto& [id, chain] : chains_) {
    chain_col[id] = cols;
    cols += 3 * static_cast<int>(chain.states.size());
  }
  auto robot_col = [](int t) { return t == 0 ? -1 : 3 * (t - 1); };
  const Eigen::Vector3d robot_w = robot_var_.unaryExpr(&Sd).cwiseInverse();
  const Eigen::Vector3d landmark_w = landmark_var_.unaryExpr(&Sd).cwiseInverse();
  const Eigen::Vector2d z_w(1.0 / Sd(var_r_), 1.0 / Sd(var_b_));

  auto build = [&](Rows* rows) {
    for (int t = 1; t <= steps; ++t) {
      const auto f = [&](const Pose2& x) { return StepRobot(x, t); };
      const Eigen::Vector3d r = robot_w.asDiagonal() * Minus(path_[t], f(path_[t - 1]));
      const Eigen::Matrix3d jf = -(robot_w.asDiagonal() * NumericJacobian(f, path_[t - 1]));
      rows->Add(r, {{robot_col(t), Eigen::MatrixXd(robot_w.asDiagonal())}, {robot_col(t - 1), jf}});
    }
    for (const auto& [id, chain] : chains_) {
      const int base = chain_col[id];
      // A weak prior on the first heading keeps it defined before it is observable.
      Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(1, 3);
      prior(0, 2) = 1e-3;
      rows->Add(Eigen::VectorXd::Zero(1), {{base, prior}});
      const Kinematics& k = chain.kinematics;
      const auto f = [&](const Pose2& l) { return StepLandmark(l, k); };
      // A static landmark stays put: a stiff constraint between its steps' states.
      const Eigen::Vector3d w = k.is_static ? Eigen::Vector3d::Constant(1e4) : landmark_w;
      for (std::size_t i = 1; i < chain.states.size(); ++i) {
        const Eigen::Vector3d r = w.asDiagonal() * Minus(chain.states[i], f(chain.states[i - 1]));
        const Eigen::Matrix3d jf = -(w.asDiagonal() * NumericJacobian(f, chain.states[i - 1]));
        const int col = base + 3 * static_cast<int>(i);
        rows->Add(r, {{col, Eigen::MatrixXd(w.asDiagonal())}, {col - 3, jf}});
      }
    }
    for (const Reading& z : readings_) {
      const Chain& chain = chains_.at(z.landmark_id);
      const Pose2& x = path_[z.step];
      const Pose2& l = chain.states[z.step - chain.first_step];
      const double dx = l.x - x.x, dy = l.y - x.y, q = dx * dx + dy * dy, range = std::sqrt(q);
      const Eigen::Vector2d r(z_w(0) * (z.range_m - range),
                              z_w(1) * WrapAngle(z.bearing_rad - (std::atan2(dy, dx) - x.heading)));
      // Jacobians of the residual (z - h): -dh.
      Eigen::MatrixXd jx(2, 3), jl(2, 3);
      jx << dx / range, dy / range, 0.0, -dy / q, dx / q, 1.0;
      jl << -dx / range, -dy / range, 0.0, dy / q, -dx / q, 0.0;
      jx = z_w.asDiagonal() * jx;
      jl = z_w.asDiagonal() * jl;
      rows->Add(r, {{robot_col(z.step), jx}, {chain_col[z.landmark_id] + 3 * (z.step - chain.first_step), jl}});
    }
  };
  auto cost = [](const Rows& rows) {
    double c = 0.0;
    for (const double r : rows.residual) c += r * r;
    return c;
  };
  auto apply = [&](const Eigen::VectorXd& delta, double sign) {
    for (int t = 1; t <= steps; ++t) {
      path_[t] = Pose2::FromVector(path_[t].Vector() + sign * delta.segment<3>(robot_col(t)));
    }
    for (auto& [id, chain] : chains_) {
      for (std::size_t i = 0; i < chain.states.size(); ++i) {
        const int col = chain_col[id] + 3 * static_cast<int>(i);
        chain.states[i] = Pose2::FromVector(chain.states[i].Vector() + sign * delta.segment<3>(col));
      }
    }
  };

  double lambda = 1e-6;
  for (int iteration = 0; iteration < 30; ++iteration) {
    Rows rows;
    build(&rows);
    const double before = cost(rows);
    Eigen::SparseMatrix<double> j(static_cast<int>(rows.residual.size()), cols);
    j.setFromTriplets(rows.jacobian.begin(), rows.jacobian.end());
    const Eigen::Map<const Eigen::VectorXd> r(rows.residual.data(), static_cast<int>(rows.residual.size()));
    Eigen::SparseMatrix<double> h = j.transpose() * j;
    const Eigen::VectorXd g = j.transpose() * r;
    Eigen::VectorXd diag = h.diagonal();
    for (int c = 0; c < cols; ++c) h.coeffRef(c, c) += lambda * std::max(diag(c), 1e-9);
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(h);
    // The residual is z - h(.) style (r = target - model), so the step solves H d = -J^T r.
    const Eigen::VectorXd delta = solver.solve(-g);
    if (solver.info() != Eigen::Success || !delta.allFinite()) break;
    apply(delta, 1.0);
    Rows after_rows;
    build(&after_rows);
    const double after = cost(after_rows);
    if (after > before) {
      apply(delta, -1.0);
      lambda *= 10.0;
      if (lambda > 1e6) break;
      continue;
    }
    lambda = std::max(lambda / 10.0, 1e-9);
    if (delta.cwiseAbs().maxCoeff() < 1e-7) break;
  }
  for (auto& x : path_) x.heading = WrapAngle(x.heading);
  for (auto& [id, chain] : chains_) {
    for (auto& l : chain.states) l.heading = WrapAngle(l.heading);
  }
}

std::vector<std::pair<Eigen::Vector2d, int>> MapReference::Landmarks() const {
  std::vector<std::pair<Eigen::Vector2d, int>> out;
  for (const auto& [id, chain] : chains_) out.emplace_back(chain.states.back().Translation(), id);
  return out;
}

}  // namespace mrslam::batch
