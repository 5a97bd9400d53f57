#include "robot_agent/smoother/block_ordering.h"

#include <cstddef>
#include <vector>

#include <Eigen/OrderingMethods>

namespace mrslam::robot_agent::smoother {
namespace {

using Matrix = Eigen::SparseMatrix<double>;

// Whether columns a and b hold entries in the same rows.
bool SamePattern(const Matrix& c, int a, int b) {
  Matrix::InnerIterator ia(c, a), ib(c, b);
  for (; ia && ib; ++ia, ++ib) {
    if (ia.row() != ib.row()) return false;
  }
  return !ia && !ib;
}

}  // namespace

void BlockAmdOrdering::operator()(const Matrix& c, PermutationType& perm) const {
  const int n = static_cast<int>(c.cols());
  std::vector<int> group(static_cast<std::size_t>(n));
  std::vector<int> first;  // each supervariable's first column
  for (int j = 0; j < n; ++j) {
    if (j == 0 || !SamePattern(c, j - 1, j)) first.push_back(j);
    group[j] = static_cast<int>(first.size()) - 1;
  }
  const int groups = static_cast<int>(first.size());
  first.push_back(n);
  // The supervariables' graph, its diagonal included (the ordering needs it).
  std::vector<Eigen::Triplet<double>> entries;
  for (int g = 0; g < groups; ++g) {
    entries.emplace_back(g, g, 1.0);
    int last = -1;
    for (Matrix::InnerIterator it(c, first[g]); it; ++it) {
      const int h = group[it.row()];
      if (h != last && h != g) entries.emplace_back(h, g, 1.0);
      last = h;
    }
  }
  Matrix graph(groups, groups);
  graph.setFromTriplets(entries.begin(), entries.end());
  PermutationType order;
  Eigen::internal::minimum_degree_ordering(graph, order);
  perm.resize(n);
  int k = 0;
  for (int i = 0; i < groups; ++i) {
    const int g = order.indices()[i];
    for (int j = first[g]; j < first[g + 1]; ++j) perm.indices()[k++] = j;
  }
}

}  // namespace mrslam::robot_agent::smoother
