#include "world_sim/core/landmark_motion.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "common/angles.h"
#include "world_sim/core/world.h"

namespace mrslam::world_sim {

SimLandmark::SimLandmark(const common::LandmarkOptions& options, std::uint64_t seed)
    : options_(options), pose_(options.pose), rng_(seed, "landmark/" + std::to_string(options.id)) {}

void SimLandmark::Step(double dt_s, const Eigen::Vector3d& process_var) {
  const auto& m = options_.motion;
  switch (m.model) {
    case common::LandmarkMotionModel::kStatic:
      return;
    case common::LandmarkMotionModel::kUnicycle:
      pose_ = common::UnicycleStep(pose_, m.v_mps, m.w_radps, dt_s);
      pose_.x += rng_.Normal(0.0, std::sqrt(process_var.x()));
      pose_.y += rng_.Normal(0.0, std::sqrt(process_var.y()));
      pose_.heading = common::WrapAngle(pose_.heading + rng_.Normal(0.0, std::sqrt(process_var.z())));
      break;
    case common::LandmarkMotionModel::kCardinal:
      // p += s dt (cos h, sin h); h reverses (h += pi) after every N-th step, so the landmark
      // goes N steps one way and N steps back.
      pose_.x += m.speed_mps * dt_s * std::cos(pose_.heading) + rng_.Normal(0.0, std::sqrt(process_var.x()));
      pose_.y += m.speed_mps * dt_s * std::sin(pose_.heading) + rng_.Normal(0.0, std::sqrt(process_var.y()));
      if (m.reverse_every_steps > 0 && (steps_taken_ + 1) % m.reverse_every_steps == 0) {
        pose_.heading = common::WrapAngle(pose_.heading + common::kPi);
      }
      break;
    case common::LandmarkMotionModel::kConstantVelocity:
      // p += v dt.
      pose_.x += m.velocity_mps.x() * dt_s + rng_.Normal(0.0, std::sqrt(process_var.x()));
      pose_.y += m.velocity_mps.y() * dt_s + rng_.Normal(0.0, std::sqrt(process_var.y()));
      break;
  }
  ++steps_taken_;
}

std::vector<common::LandmarkOptions> ExpandLandmarks(const common::ScenarioOptions& options) {
  std::vector<common::LandmarkOptions> landmarks = options.landmarks;
  const auto& field = options.landmark_field;
  if (!field.enabled || field.count <= 0) return landmarks;

  common::Rng rng(options.seed, "landmark_field");
  const double x_min = field.area_m[0], y_min = field.area_m[1];
  const double width_m = field.area_m[2] - x_min, height_m = field.area_m[3] - y_min;
  // As square a grid as the aspect allows: cols / rows ~ width / height with cols * rows ~ n,
  // so cols = ceil(sqrt(n * width / height)), rows = ceil(n / cols) (cols * rows >= n).
  const int n = field.count;
  const int cols = std::clamp(static_cast<int>(std::ceil(std::sqrt(n * width_m / height_m) - 1e-9)), 1, n);
  const int rows = (n + cols - 1) / cols;
  const int cells = cols * rows;
  const double cell_w_m = width_m / cols, cell_h_m = height_m / rows;

  const std::size_t first = landmarks.size();
  for (int i = 0; i < n; ++i) {
    // Landmark i takes cell floor(i * cells / n): spare cells are spread over the grid.
    const int cell = static_cast<int>(static_cast<long long>(i) * cells / n);
    const int c = cell % cols, r = cell / cols;
    common::LandmarkOptions l;
    l.id = field.first_id + i;
    l.pose.x = x_min + (c + 0.5) * cell_w_m + rng.Uniform(-field.jitter_m, field.jitter_m);
    l.pose.y = y_min + (r + 0.5) * cell_h_m + rng.Uniform(-field.jitter_m, field.jitter_m);
    l.pose.heading = 0.0;
    landmarks.push_back(l);
  }

  // A seeded subset of round(fraction * n) landmarks moves: the first picks of a Fisher-Yates
  // shuffle of the indices.
  const int moving = std::clamp(static_cast<int>(std::lround(field.moving_fraction * n)), 0, n);
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  for (int i = 0; i < moving; ++i) {
    std::swap(order[i], order[rng.UniformInt(i, n - 1)]);
  }
  constexpr double kCardinalHeadings[] = {0.0, common::kPi / 2.0, common::kPi, -common::kPi / 2.0};
  for (int i = 0; i < moving; ++i) {
    auto& l = landmarks[first + order[i]];
    l.motion.model = common::LandmarkMotionModel::kCardinal;
    l.motion.speed_mps = field.speed_mps;
    l.motion.reverse_every_steps = field.reverse_every_steps;
    l.pose.heading = kCardinalHeadings[rng.UniformInt(0, 3)];
  }
  return landmarks;
}

}  // namespace mrslam::world_sim
