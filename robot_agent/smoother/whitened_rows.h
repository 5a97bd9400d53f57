#pragma once

#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace mrslam::robot_agent::smoother {

// The whitened residual rows of a least-squares problem and their Jacobian as triplets: the
// cost is the sum of squared residuals, J = d residual / d unknowns. Each Add appends one
// block: r (size n) and its Jacobian blocks (n x k each, zeros kept so the pattern depends on
// the structure only) at the given column offsets (-1: a known quantity, no column).
struct WhitenedRows {
  std::vector<Eigen::Triplet<double>> jacobian;
  std::vector<double> residual;

  void Add(const Eigen::VectorXd& r, const std::vector<std::pair<int, Eigen::MatrixXd>>& blocks) {
    const int row = static_cast<int>(residual.size());
    for (int i = 0; i < r.size(); ++i) residual.push_back(r(i));
    for (const auto& [col, j] : blocks) {
      if (col < 0) continue;
      for (int i = 0; i < j.rows(); ++i) {
        for (int c = 0; c < j.cols(); ++c) jacobian.emplace_back(row + i, col + c, j(i, c));
      }
    }
  }
  double Cost() const {
    double c = 0.0;
    for (const double r : residual) c += r * r;
    return c;
  }
  Eigen::SparseMatrix<double> Matrix(int cols) const {
    Eigen::SparseMatrix<double> j(static_cast<int>(residual.size()), cols);
    j.setFromTriplets(jacobian.begin(), jacobian.end());
    return j;
  }
};

}  // namespace mrslam::robot_agent::smoother
