#pragma once

#include <functional>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "robot_agent/smoother/block_ordering.h"
#include "robot_agent/smoother/normal_equations.h"

namespace mrslam::robot_agent::smoother {

// LDL^T with the fill-reducing ordering of the variables (block_ordering.h).
using Factorization = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, BlockAmdOrdering>;

// A least-squares problem as Levenberg-Marquardt sees it: its normal equations at the current
// values (only the cost without jacobians), and the values moved by a step, kept or put back.
struct LeastSquares {
  int cols = 0;
  std::function<NormalEquations(bool jacobians)> equations;
  std::function<void(const Eigen::VectorXd& delta)> step;  // x += delta (angles wrapped by the caller)
  std::function<void()> save, restore;                     // the values before a step, and back to them
  double min_step = 1e-7, min_relative_decrease = 1e-6;    // convergence: see LevenbergMarquardt
};

struct LmResult {
  double cost = 0.0;
  double factorized_lambda = 0.0;  // the damping of the last factorization
  bool factorized = false;         // the last factorization succeeded

  // Whether the last factorization can stand for the information matrix at the solution: it
  // succeeded, damped by at most 1e-4 (it is linearized where the last iteration started).
  bool InformationUsable() const { return factorized && factorized_lambda <= 1e-4; }
};

// Levenberg-Marquardt on the sparse normal equations H = J^T J (+ priors), g = J^T r: at most
// max_iterations times, solve (H + lambda diag(H) + ridge I) delta = -g (diag floored at 1e-9),
// keep the step if the cost falls (lambda / 10, at least 1e-9), else put it back (lambda x 10;
// give up beyond 1e6) and damp the same normal equations again, not rebuilt at the same point; stop once the step's
// largest entry is below min_step or the cost falls by less than min_relative_decrease (1 + cost). Lambda starts at
// 1e-6. The ridge keeps a variable nothing informs from making H singular. `solver` keeps the last factorization (for
// covariances).
LmResult LevenbergMarquardt(const LeastSquares& problem, int max_iterations, double ridge, Factorization* solver);

}  // namespace mrslam::robot_agent::smoother
