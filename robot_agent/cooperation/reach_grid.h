#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "common/archive.h"
#include "common/se2.h"

namespace mrslam::robot_agent::cooperation {

// The places a robot's lidar has reached: square cells of side cell_m in its own frame, marked
// on a dense grid that grows to cover what is marked (its size follows the area explored, not
// the run's length), at most kMaxCellsPerAxis cells along each axis: a view that would grow it
// beyond (or from a pose not finite) is not marked.
class ReachGrid {
 public:
  static constexpr std::int32_t kMaxCellsPerAxis = 4096;

  explicit ReachGrid(double cell_m);

  // Marks every cell whose centre lies within range_m of pose and within half_fov_rad of its
  // heading (widened by margin_m at the centre's range; a full circle for a field of view of 2 pi).
  void Mark(const common::Pose2& pose, double range_m, double half_fov_rad, double margin_m);
  // Whether a marked cell's centre lies within radius_m of p.
  bool AnyWithin(const Eigen::Vector2d& p, double radius_m) const;

  std::size_t Bytes() const { return cells_.size() * sizeof(std::uint8_t); }
  void Io(common::Archive& ar) { ar(i0_, j0_, ni_, nj_, cells_); }

 private:
  std::int32_t Index(double x) const;
  // Grows the grid to hold cells [i_lo, i_hi] x [j_lo, j_hi]; false (unchanged) when it would
  // exceed kMaxCellsPerAxis.
  bool Cover(std::int32_t i_lo, std::int32_t j_lo, std::int32_t i_hi, std::int32_t j_hi);
  bool Marked(std::int32_t i, std::int32_t j) const;
  Eigen::Vector2d Centre(std::int32_t i, std::int32_t j) const;

  double cell_m_;
  std::int32_t i0_ = 0, j0_ = 0;     // the first cell's indices
  std::int32_t ni_ = 0, nj_ = 0;     // cells along x and y
  std::vector<std::uint8_t> cells_;  // 1: marked; cell (i, j) at (j - j0) * ni + (i - i0)
};

}  // namespace mrslam::robot_agent::cooperation
