#include "robot_agent/filters/reachable_landmarks.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "robot_agent/filters/association.h"

namespace mrslam::robot_agent::filters {

template <int D>
std::uint32_t ReachableLanes(const LandmarkBlock<D>& block, int count, const Eigen::Vector2d& xy, double pose_var_xy,
                             double z_min, double z_max, const ReachRule& rule) {
  constexpr double kSlack = 1.0 + 1e-6;
  std::uint32_t lanes = 0;
  for (int l = 0; l < count; ++l) {
    const double s_rr = rule.euclidean ? 1.0 : block.Cov(0, 0, l) + block.Cov(1, 1, l) + pose_var_xy + rule.var_r;
    const double reach = std::sqrt(rule.gate * s_rr) * kSlack + rule.shift_m;
    const double dx = block.Mean(0, l) - xy.x(), dy = block.Mean(1, l) - xy.y();
    const double r2 = dx * dx + dy * dy, far = z_max + reach, near = z_min - reach;
    // Written so that a landmark whose range is not a number counts as reachable, as it would
    // be gated.
    const bool out = r2 > far * far || (near > 0.0 && r2 < near * near);
    if (!out) lanes |= 1U << l;
  }
  return lanes;
}

template <int D>
void ReachableLandmarks<D>::StartStep(double z_min, double z_max) {
  z_min_ = z_min;
  z_max_ = z_max;
  valid_ = false;
}

template <int D>
void ReachableLandmarks<D>::Gather(const std::vector<std::shared_ptr<LandmarkBlock<D>>>& blocks, int count,
                                   const Eigen::Vector2d& xy, double pose_var_xy) {
  center_ = xy;
  pose_var_xy_ = pose_var_xy;
  valid_ = true;
  slots_.clear();
  for (int b = 0; b * kLanes < count; ++b) {
    const LandmarkBlock<D>& block = *blocks[b];
    std::uint32_t lanes =
        ReachableLanes(block, std::min(kLanes, count - b * kLanes), xy, pose_var_xy, z_min_, z_max_, rule_);
    for (; lanes != 0; lanes &= lanes - 1) {
      const int lane = __builtin_ctz(lanes);
      const int n = size();
      if (n / kLanes >= static_cast<int>(blocks_.size())) blocks_.emplace_back();
      LandmarkBlock<2>& to = blocks_[n / kLanes];
      const int to_lane = n % kLanes;
      to.Mean(0, to_lane) = block.Mean(0, lane);
      to.Mean(1, to_lane) = block.Mean(1, lane);
      to.Cov(0, 0, to_lane) = block.Cov(0, 0, lane);
      to.Cov(0, 1, to_lane) = block.Cov(0, 1, lane);
      to.Cov(1, 1, to_lane) = block.Cov(1, 1, lane);
      slots_.push_back(b * kLanes + lane);
    }
  }
}

template <int D>
std::pair<int, double> ReachableLandmarks<D>::Nearest(const std::vector<std::shared_ptr<LandmarkBlock<D>>>& blocks,
                                                      int count, const common::Pose2& pose,
                                                      const Eigen::Matrix3d& sigma, double z_r, double z_b,
                                                      const std::vector<std::uint8_t>& used) {
  int nearest = -1;       // among the d2_ computed
  if (count <= kLanes) {  // one block: gated as it is, nothing to gain by gathering
    d2_.resize(kLanes);
    GateBlock(*blocks[0], count, pose, sigma, z_r, z_b, rule_.var_r, rule_.var_b, rule_.euclidean, d2_.data());
    nearest = NearestUnused(d2_.data(), count, used);
  } else {
    GateGathered(blocks, count, pose, sigma, z_r, z_b);
    nearest = NearestUnusedOf(d2_.data(), size(), [&](int i) { return used[slots_[i]] != 0; });
  }
  if (nearest < 0) return {-1, std::numeric_limits<double>::infinity()};
  return {count <= kLanes ? nearest : slots_[nearest], d2_[nearest]};
}

template <int D>
void ReachableLandmarks<D>::GateGathered(const std::vector<std::shared_ptr<LandmarkBlock<D>>>& blocks, int count,
                                         const common::Pose2& pose, const Eigen::Matrix3d& sigma, double z_r,
                                         double z_b) {
  const Eigen::Vector2d xy(pose.x, pose.y);
  const double pose_var_xy = sigma(0, 0) + sigma(1, 1);
  if (!valid_ || (xy - center_).norm() > rule_.shift_m || pose_var_xy > pose_var_xy_) {
    Gather(blocks, count, xy, pose_var_xy);
  }
  const int n = size();
  d2_.resize(static_cast<std::size_t>((n + kLanes - 1) / kLanes) * kLanes);
  for (int b = 0; b * kLanes < n; ++b) {
    GateBlock(blocks_[b], std::min(kLanes, n - b * kLanes), pose, sigma, z_r, z_b, rule_.var_r, rule_.var_b,
              rule_.euclidean, &d2_[static_cast<std::size_t>(b) * kLanes]);
  }
}

#define MRSLAM_REACHABLE_LANDMARKS(D)                                                                            \
  template std::uint32_t ReachableLanes<D>(const LandmarkBlock<D>&, int, const Eigen::Vector2d&, double, double, \
                                           double, const ReachRule&);                                            \
  template class ReachableLandmarks<D>;
MRSLAM_REACHABLE_LANDMARKS(2)
MRSLAM_REACHABLE_LANDMARKS(3)
MRSLAM_REACHABLE_LANDMARKS(5)
#undef MRSLAM_REACHABLE_LANDMARKS

}  // namespace mrslam::robot_agent::filters
