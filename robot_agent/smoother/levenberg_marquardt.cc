#include "robot_agent/smoother/levenberg_marquardt.h"

#include <algorithm>

namespace mrslam::robot_agent::smoother {

LmResult LevenbergMarquardt(const LeastSquares& problem, int max_iterations, double ridge, Factorization* solver) {
  LmResult out;
  double lambda = 1e-6;
  // The normal equations at the current point: after a step put back, the point is the same and
  // so are they.
  Eigen::SparseMatrix<double> h0;
  Eigen::VectorXd g, diag;
  bool current = false;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (!current) {
      const NormalEquations rows = problem.equations(true);
      h0 = rows.Matrix();
      g = rows.g;
      out.cost = rows.cost;
      diag = h0.diagonal();
      current = true;
    }
    Eigen::SparseMatrix<double> h = h0;
    for (int c = 0; c < problem.cols; ++c) h.coeffRef(c, c) += lambda * std::max(diag(c), 1e-9) + ridge;
    if (iteration == 0) solver->analyzePattern(h);
    solver->factorize(h);
    out.factorized_lambda = lambda;
    out.factorized = solver->info() == Eigen::Success;
    const Eigen::VectorXd delta = solver->solve(-g);
    if (!out.factorized || !delta.allFinite()) break;
    problem.save();
    problem.step(delta);
    const double after = problem.equations(false).cost;
    if (after > out.cost) {
      problem.restore();
      lambda *= 10.0;
      if (lambda > 1e6) break;
      continue;
    }
    const double decrease = out.cost - after;
    out.cost = after;
    current = false;
    lambda = std::max(lambda / 10.0, 1e-9);
    if (delta.cwiseAbs().maxCoeff() < problem.min_step || decrease < problem.min_relative_decrease * (1.0 + out.cost)) {
      break;
    }
  }
  return out;
}

}  // namespace mrslam::robot_agent::smoother
