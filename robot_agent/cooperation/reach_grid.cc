#include "robot_agent/cooperation/reach_grid.h"

#include <algorithm>
#include <cmath>

namespace mrslam::robot_agent::cooperation {

ReachGrid::ReachGrid(double cell_m) : cell_m_(cell_m) {}

std::int32_t ReachGrid::Index(double x) const {
  constexpr double kLimit = 1 << 30;  // far beyond any grid, within int32
  return static_cast<std::int32_t>(std::clamp(std::floor(x / cell_m_), -kLimit, kLimit));
}

Eigen::Vector2d ReachGrid::Centre(std::int32_t i, std::int32_t j) const {
  return {(i + 0.5) * cell_m_, (j + 0.5) * cell_m_};
}

bool ReachGrid::Marked(std::int32_t i, std::int32_t j) const {
  if (i < i0_ || j < j0_ || i >= i0_ + ni_ || j >= j0_ + nj_) return false;
  return cells_[static_cast<std::size_t>(j - j0_) * static_cast<std::size_t>(ni_) +
                static_cast<std::size_t>(i - i0_)] != 0;
}

bool ReachGrid::Cover(std::int32_t i_lo, std::int32_t j_lo, std::int32_t i_hi, std::int32_t j_hi) {
  if (ni_ > 0 && i_lo >= i0_ && j_lo >= j0_ && i_hi < i0_ + ni_ && j_hi < j0_ + nj_) return true;
  const auto span = [](std::int64_t lo, std::int64_t hi) { return hi - lo + 1; };
  const std::int64_t need_i = ni_ == 0 ? span(i_lo, i_hi) : span(std::min(i_lo, i0_), std::max(i_hi, i0_ + ni_ - 1));
  const std::int64_t need_j = nj_ == 0 ? span(j_lo, j_hi) : span(std::min(j_lo, j0_), std::max(j_hi, j0_ + nj_ - 1));
  if (need_i > kMaxCellsPerAxis || need_j > kMaxCellsPerAxis) return false;
  // Grown with slack on the sides it grows, so that a robot moving on is not copied every step.
  const auto room = static_cast<std::int32_t>((kMaxCellsPerAxis - std::max(need_i, need_j)) / 2);
  const std::int32_t slack = std::min(std::max<std::int32_t>(8, std::max(ni_, nj_) / 2), room);
  const std::int32_t new_i0 = ni_ == 0 ? i_lo - slack : std::min(i0_, i_lo - (i_lo < i0_ ? slack : 0));
  const std::int32_t new_j0 = nj_ == 0 ? j_lo - slack : std::min(j0_, j_lo - (j_lo < j0_ ? slack : 0));
  const std::int32_t new_i1 = ni_ == 0 ? i_hi + slack : std::max(i0_ + ni_ - 1, i_hi + (i_hi >= i0_ + ni_ ? slack : 0));
  const std::int32_t new_j1 = nj_ == 0 ? j_hi + slack : std::max(j0_ + nj_ - 1, j_hi + (j_hi >= j0_ + nj_ ? slack : 0));
  const std::int32_t new_ni = new_i1 - new_i0 + 1, new_nj = new_j1 - new_j0 + 1;
  std::vector<std::uint8_t> grown(static_cast<std::size_t>(new_ni) * static_cast<std::size_t>(new_nj), 0);
  for (std::int32_t j = j0_; j < j0_ + nj_; ++j) {
    for (std::int32_t i = i0_; i < i0_ + ni_; ++i) {
      grown[static_cast<std::size_t>(j - new_j0) * static_cast<std::size_t>(new_ni) +
            static_cast<std::size_t>(i - new_i0)] = Marked(i, j) ? 1 : 0;
    }
  }
  cells_ = std::move(grown);
  i0_ = new_i0;
  j0_ = new_j0;
  ni_ = new_ni;
  nj_ = new_nj;
  return true;
}

void ReachGrid::Mark(const common::Pose2& pose, double range_m, double half_fov_rad, double margin_m) {
  const double reach_m = range_m + margin_m;
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.heading) || !std::isfinite(reach_m)) {
    return;
  }
  const std::int32_t i_lo = Index(pose.x - reach_m), i_hi = Index(pose.x + reach_m);
  const std::int32_t j_lo = Index(pose.y - reach_m), j_hi = Index(pose.y + reach_m);
  if (!Cover(i_lo, j_lo, i_hi, j_hi)) return;
  for (std::int32_t j = j_lo; j <= j_hi; ++j) {
    for (std::int32_t i = i_lo; i <= i_hi; ++i) {
      const common::RangeBearing h = common::MeasureRangeBearing(pose, Centre(i, j));
      if (h.range_m > reach_m || std::abs(h.bearing_rad) > half_fov_rad + margin_m / std::max(h.range_m, margin_m)) {
        continue;
      }
      cells_[static_cast<std::size_t>(j - j0_) * static_cast<std::size_t>(ni_) + static_cast<std::size_t>(i - i0_)] = 1;
    }
  }
}

bool ReachGrid::AnyWithin(const Eigen::Vector2d& p, double radius_m) const {
  if (ni_ == 0 || !p.allFinite() || !std::isfinite(radius_m)) return false;
  const std::int32_t i_lo = std::max(i0_, Index(p.x() - radius_m));
  const std::int32_t i_hi = std::min(i0_ + ni_ - 1, Index(p.x() + radius_m));
  const std::int32_t j_lo = std::max(j0_, Index(p.y() - radius_m));
  const std::int32_t j_hi = std::min(j0_ + nj_ - 1, Index(p.y() + radius_m));
  for (std::int32_t j = j_lo; j <= j_hi; ++j) {
    for (std::int32_t i = i_lo; i <= i_hi; ++i) {
      if (Marked(i, j) && (Centre(i, j) - p).norm() <= radius_m) return true;
    }
  }
  return false;
}

}  // namespace mrslam::robot_agent::cooperation
