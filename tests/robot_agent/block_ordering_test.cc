#include "robot_agent/smoother/block_ordering.h"

#include <algorithm>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/SparseCholesky>

namespace mrslam::robot_agent::smoother {
namespace {

// A hub variable (3 columns, first) tied to every other variable, the others (3 and 2 columns
// in turn) tied in a chain: the normal equations' shape of a pose graph with one landmark that
// every pose reads. Every block whole (structural zeros included), diagonally dominant.
struct Problem {
  std::vector<int> first, dims;   // each variable's first column and size
  Eigen::SparseMatrix<double> h;  // both triangles
};

Problem HubAndChain(int others) {
  Problem p;
  int cols = 0;
  for (int v = 0; v <= others; ++v) {
    p.first.push_back(cols);
    p.dims.push_back(v % 2 == 0 ? 3 : 2);
    cols += p.dims.back();
  }
  std::vector<Eigen::Triplet<double>> t;
  const auto tie = [&](int a, int b, double value) {
    for (int i = 0; i < p.dims[a]; ++i) {
      for (int j = 0; j < p.dims[b]; ++j) {
        t.emplace_back(p.first[a] + i, p.first[b] + j, value);
        if (a != b) t.emplace_back(p.first[b] + j, p.first[a] + i, value);
      }
    }
  };
  for (int v = 0; v <= others; ++v) tie(v, v, 0.0);
  for (int v = 1; v <= others; ++v) tie(0, v, 0.1);
  for (int v = 2; v <= others; ++v) tie(v - 1, v, 0.2);
  p.h.resize(cols, cols);
  p.h.setFromTriplets(t.begin(), t.end());
  for (int c = 0; c < cols; ++c) p.h.coeffRef(c, c) = 10.0 + c;
  return p;
}

TEST(BlockAmdOrdering, IsAPermutationThatKeepsEachVariableWhole) {
  const Problem p = HubAndChain(20);
  BlockAmdOrdering::PermutationType perm;
  BlockAmdOrdering()(p.h, perm);
  const int n = static_cast<int>(p.h.cols());
  ASSERT_EQ(perm.size(), n);
  std::vector<int> seen(perm.indices().data(), perm.indices().data() + n);
  std::sort(seen.begin(), seen.end());
  for (int c = 0; c < n; ++c) EXPECT_EQ(seen[c], c);
  std::vector<int> position(n);
  for (int k = 0; k < n; ++k) position[perm.indices()[k]] = k;
  for (std::size_t v = 0; v < p.first.size(); ++v) {
    for (int i = 1; i < p.dims[v]; ++i) {
      EXPECT_EQ(position[p.first[v] + i], position[p.first[v]] + i) << "variable " << v;
    }
  }
  // The hub, tied to everything, is not eliminated first.
  EXPECT_GT(position[p.first[0]], 0);
}

TEST(BlockAmdOrdering, FillsLessThanTheNaturalOrderAndSolvesTheSame) {
  const Problem p = HubAndChain(40);
  const Eigen::SparseMatrix<double> lower = p.h.triangularView<Eigen::Lower>();
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, BlockAmdOrdering> ordered(lower);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> natural(lower);
  ASSERT_EQ(ordered.info(), Eigen::Success);
  ASSERT_EQ(natural.info(), Eigen::Success);
  const Eigen::SparseMatrix<double> l_ordered = ordered.matrixL();
  const Eigen::SparseMatrix<double> l_natural = natural.matrixL();
  // Eliminating the hub first fills the whole factor; last, the chain stays a band.
  EXPECT_LT(2 * l_ordered.nonZeros(), l_natural.nonZeros());
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(p.h.cols(), -1.0, 1.0);
  EXPECT_LT((ordered.solve(b) - natural.solve(b)).norm(), 1e-12);
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
