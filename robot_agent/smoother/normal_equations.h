#pragma once

#include <initializer_list>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace mrslam::robot_agent::smoother {

// The Gauss-Newton normal equations of a sum of whitened residual blocks, built block by block
// without forming the Jacobian: the lower triangle of H = sum J^T J (triplets with row >= column,
// summed when made a matrix; H is symmetric), g = sum J^T r, and the cost the caller adds (a
// robust loss's may differ from |r|^2). A block is r
// (size n) and its Jacobian blocks (n x k) at column offsets (-1: a known quantity, no column).
// With jacobians false only the cost is kept.
// Blocks are at most 3 x 3 (poses, landmark states), held without heap allocation.
struct NormalEquations {
  using Residual = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;

  NormalEquations(int cols, bool with_jacobians) : jacobians(with_jacobians), g(Eigen::VectorXd::Zero(cols)) {}

  void Add(const Residual& r, std::initializer_list<std::pair<int, Block>> blocks) {
    if (!jacobians) return;
    for (const auto& [col_a, ja] : blocks) {
      if (col_a < 0) continue;
      g.segment(col_a, ja.cols()) += ja.transpose() * r;
      for (const auto& [col_b, jb] : blocks) {
        if (col_b < 0 || col_b > col_a) continue;
        const Block m = ja.transpose() * jb;
        for (int i = 0; i < m.rows(); ++i) {
          for (int j = 0; j < (col_a == col_b ? i + 1 : m.cols()); ++j) h.emplace_back(col_a + i, col_b + j, m(i, j));
        }
      }
    }
  }
  // A plain least-squares block: its cost |r|^2 and its normal equations.
  void AddSquared(const Residual& r, std::initializer_list<std::pair<int, Block>> blocks) {
    cost += r.squaredNorm();
    Add(r, blocks);
  }
  // H's lower triangle (for a solver that reads only that, or selfadjointView<Lower>).
  Eigen::SparseMatrix<double> Matrix() const {
    Eigen::SparseMatrix<double> out(static_cast<int>(g.size()), static_cast<int>(g.size()));
    out.setFromTriplets(h.begin(), h.end());
    return out;
  }

  bool jacobians;
  double cost = 0.0;
  Eigen::VectorXd g;
  std::vector<Eigen::Triplet<double>> h;
};

}  // namespace mrslam::robot_agent::smoother
