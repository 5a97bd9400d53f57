#include "world_sim/evaluator/metrics.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

#include "common/angles.h"
#include "common/gaussian.h"

namespace mrslam::evaluator {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

std::vector<LandmarkMatch> MatchLandmarks(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                                          const common::Pose2& frame_in_world, double cutoff_m) {
  assert(cutoff_m > 0.0);
  // p_G = T(G <- W) p_W with T(G <- W) = T(W <- G)^-1.
  const common::Pose2 world_in_frame = common::Inverse(frame_in_world);
  std::vector<Eigen::Vector2d> truth_in_frame(truth.size());
  std::unordered_map<int, int> index_of_id;
  for (size_t k = 0; k < truth.size(); ++k) {
    truth_in_frame[k] = common::TransformPoint(world_in_frame, truth[k].position_m);
    index_of_id.emplace(truth[k].landmark_id, static_cast<int>(k));  // first one wins
  }

  // A pair (map landmark, true landmark) at distance d: matched if d <= cut-off, else the map
  // landmark counts as unmatched with error cut-off.
  auto pair_match = [&](size_t m, int k) {
    const double d = (map[m].position_m - truth_in_frame[k]).norm();
    return d <= cutoff_m ? LandmarkMatch{k, d} : LandmarkMatch{-1, cutoff_m};
  };

  std::vector<LandmarkMatch> matches(map.size(), LandmarkMatch{-1, cutoff_m});
  std::vector<bool> claimed(truth.size(), false);
  std::vector<size_t> free_map;
  for (size_t m = 0; m < map.size(); ++m) {
    const auto it = map[m].landmark_id >= 0 ? index_of_id.find(map[m].landmark_id) : index_of_id.end();
    if (it == index_of_id.end()) {
      free_map.push_back(m);
      continue;
    }
    claimed[it->second] = true;
    matches[m] = pair_match(m, it->second);
  }
  std::vector<int> free_truth;
  for (size_t k = 0; k < truth.size(); ++k) {
    if (!claimed[k]) free_truth.push_back(static_cast<int>(k));
  }
  if (free_map.empty() || free_truth.empty()) return matches;

  // cost(r, c) = min(d^2, cutoff^2): a pair beyond the cut-off costs what no partner costs.
  const double cutoff_sq = cutoff_m * cutoff_m;
  Eigen::MatrixXd cost(free_map.size(), free_truth.size());
  for (size_t r = 0; r < free_map.size(); ++r) {
    for (size_t c = 0; c < free_truth.size(); ++c) {
      const double d_sq = (map[free_map[r]].position_m - truth_in_frame[free_truth[c]]).squaredNorm();
      cost(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = std::min(d_sq, cutoff_sq);
    }
  }
  const std::vector<int> assignment = OptimalAssignment(cost);
  for (size_t r = 0; r < free_map.size(); ++r) {
    if (assignment[r] >= 0) {
      matches[free_map[r]] = pair_match(free_map[r], free_truth[assignment[r]]);
    }
  }
  return matches;
}

common::Pose2 TruthInOwnFrame(const common::Pose2& truth_in_world, const common::Pose2& frame_in_world) {
  return common::Compose(common::Inverse(frame_in_world), truth_in_world);
}

double PositionError(const common::Pose2& estimate, const common::Pose2& truth_in_own_frame) {
  return (estimate.Translation() - truth_in_own_frame.Translation()).norm();
}

double HeadingError(const common::Pose2& estimate, const common::Pose2& truth_in_own_frame) {
  return std::abs(common::WrapAngle(estimate.heading - truth_in_own_frame.heading));
}

double PoseNees(const common::Pose2& estimate, const Eigen::Matrix3d& covariance,
                const common::Pose2& truth_in_own_frame) {
  const Eigen::Vector3d e(estimate.x - truth_in_own_frame.x, estimate.y - truth_in_own_frame.y,
                          common::WrapAngle(estimate.heading - truth_in_own_frame.heading));
  // P = L L^T, so e^T P^-1 e = ||L^-1 e||^2.
  const Eigen::LLT<Eigen::Matrix3d> llt(covariance);
  if (llt.info() != Eigen::Success) return kNan;
  return llt.matrixL().solve(e).squaredNorm();
}

std::vector<double> LandmarkErrors(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                                   const common::Pose2& frame_in_world, double cutoff_m) {
  const std::vector<LandmarkMatch> matches = MatchLandmarks(map, truth, frame_in_world, cutoff_m);
  std::vector<double> errors;
  errors.reserve(matches.size());
  for (const LandmarkMatch& match : matches) errors.push_back(match.error_m);
  return errors;
}

std::vector<int> MatchedTruth(const std::vector<MapPoint>& map, const std::vector<TruePoint>& truth,
                              const common::Pose2& frame_in_world, double cutoff_m) {
  std::vector<bool> matched(truth.size(), false);
  for (const LandmarkMatch& match : MatchLandmarks(map, truth, frame_in_world, cutoff_m)) {
    if (match.truth_index >= 0) matched[match.truth_index] = true;
  }
  std::vector<int> indices;
  for (size_t k = 0; k < truth.size(); ++k) {
    if (matched[k]) indices.push_back(static_cast<int>(k));
  }
  return indices;
}

// Hungarian algorithm with potentials (Kuhn-Munkres in the shortest-augmenting-path form of
// Jonker-Volgenant), for n rows <= m columns; a taller matrix is solved transposed.
//
// Dual: potentials u_i (rows), v_j (columns) with u_i + v_j <= a_ij for all (i, j), and
// a_ij = u_i + v_j on every assigned pair. Rows are added one at a time; for row i a Dijkstra-
// like search over the reduced costs a_ij - u_i - v_j (all >= 0) grows a tree of alternating
// paths from i until it reaches a free column; minv_j is the smallest reduced cost reaching
// column j from the tree, way_j the tree column it was reached from. Each step moves the
// potentials by delta = min over columns outside the tree of minv_j, which keeps the duals
// feasible and makes one more column tight. The path is then flipped. At the end complementary
// slackness holds, so the assignment is optimal. O(n^2 m).
MapAgreement AgreementOfMaps(const std::map<int, MapPoint>& a, const common::Pose2& frame_a,
                             const std::map<int, MapPoint>& b, const common::Pose2& frame_b, double sd) {
  const Eigen::Matrix2d rot_a = common::ComposeJacobianRight(frame_a, {}).topLeftCorner<2, 2>();
  const Eigen::Matrix2d rot_b = common::ComposeJacobianRight(frame_b, {}).topLeftCorner<2, 2>();
  MapAgreement out;
  for (const auto& [id, pa] : a) {
    const auto it = b.find(id);
    if (it == b.end()) continue;
    const MapPoint& pb = it->second;
    const Eigen::Matrix2d c =
        rot_a * pa.covariance_m2 * rot_a.transpose() + rot_b * pb.covariance_m2 * rot_b.transpose();
    if (!common::IsSymmetricPositiveDefinite<2>(pa.covariance_m2) ||
        !common::IsSymmetricPositiveDefinite<2>(pb.covariance_m2)) {
      continue;
    }
    const Eigen::Vector2d d =
        common::TransformPoint(frame_a, pa.position_m) - common::TransformPoint(frame_b, pb.position_m);
    ++out.common;
    out.within += d.dot(c.ldlt().solve(d)) <= sd * sd ? 1 : 0;
  }
  return out;
}

std::vector<int> OptimalAssignment(const Eigen::MatrixXd& cost) {
  const Eigen::Index rows = cost.rows(), cols = cost.cols();
  std::vector<int> row_to_col(static_cast<size_t>(rows), -1);
  if (rows == 0 || cols == 0) return row_to_col;
  assert(cost.allFinite() && "OptimalAssignment: costs must be finite");
  if (!cost.allFinite()) return row_to_col;
  if (rows > cols) {
    const std::vector<int> col_to_row = OptimalAssignment(cost.transpose());
    for (Eigen::Index c = 0; c < cols; ++c) row_to_col[col_to_row[c]] = static_cast<int>(c);
    return row_to_col;
  }

  const int n = static_cast<int>(rows), m = static_cast<int>(cols);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // 1-based: column 0 is a virtual column holding the row being inserted.
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0);
  std::vector<int> row_of_col(m + 1, 0);  // 0: free
  std::vector<int> way(m + 1, 0);
  for (int i = 1; i <= n; ++i) {
    row_of_col[0] = i;
    int j0 = 0;
    std::vector<double> minv(m + 1, kInf);
    std::vector<bool> used(m + 1, false);
    do {
      used[j0] = true;
      const int i0 = row_of_col[j0];
      double delta = kInf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double reduced = cost(i0 - 1, j - 1) - u[i0] - v[j];
        if (reduced < minv[j]) {
          minv[j] = reduced;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      assert(j1 != 0);
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[row_of_col[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (row_of_col[j0] != 0);
    // Flip the alternating path ending at the free column j0.
    do {
      const int j1 = way[j0];
      row_of_col[j0] = row_of_col[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  for (int j = 1; j <= m; ++j) {
    if (row_of_col[j] != 0) row_to_col[row_of_col[j] - 1] = j - 1;
  }
  return row_to_col;
}

double Rmse(const std::vector<double>& errors) {
  if (errors.empty()) return 0.0;
  double sum_sq = 0.0;
  for (const double e : errors) sum_sq += e * e;
  return std::sqrt(sum_sq / static_cast<double>(errors.size()));
}

double RunningRmse::Value() const { return count_ == 0 ? 0.0 : std::sqrt(sum_sq_ / static_cast<double>(count_)); }

double Median(std::vector<double> values) { return Percentile(std::move(values), 50.0); }

// Sorted x_0 <= ... <= x_{n-1}, rank r = p / 100 * (n - 1), lo = floor(r):
//   P_p = x_lo + (r - lo) * (x_{lo+1} - x_lo).
double Percentile(std::vector<double> values, double p) {
  if (values.empty() || std::isnan(p)) return kNan;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(rank));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = rank - static_cast<double>(lo);
  return values[lo] + frac * (values[hi] - values[lo]);
}

TransformError FrameTransformError(const common::Pose2& t_i_j_estimate, const common::Pose2& frame_i_in_world,
                                   const common::Pose2& frame_j_in_world) {
  // T(G_i <- G_j) = T(W <- G_i)^-1 * T(W <- G_j).
  const common::Pose2 t_i_j_true = common::Between(frame_i_in_world, frame_j_in_world);
  TransformError error;
  error.translation_m = (t_i_j_estimate.Translation() - t_i_j_true.Translation()).norm();
  error.rotation_rad = std::abs(common::WrapAngle(t_i_j_estimate.heading - t_i_j_true.heading));
  return error;
}

}  // namespace mrslam::evaluator
