#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace mrslam::robot_agent::smoother {

// A fill-reducing ordering for the sparse Cholesky factorizations of the smoothers' normal
// equations: the approximate minimum degree ordering (Eigen's) of the matrix's supervariables,
// runs of adjacent columns with the same pattern (a pose's three, a landmark's two: the normal
// equations keep each variable's blocks whole, structural zeros included), each run kept
// together. On those matrices it is the ordering of the variables' graph, computed on about a
// ninth of the entries; the input is already symmetric, so A + A^T is not formed again.
// As Eigen's orderings, it gives the inverse permutation: perm.indices()[k] is the column
// eliminated k-th. Pure.
struct BlockAmdOrdering {
  using PermutationType = Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int>;
  // c: the whole symmetric matrix (both triangles), column-major.
  void operator()(const Eigen::SparseMatrix<double>& c, PermutationType& perm) const;
};

}  // namespace mrslam::robot_agent::smoother
