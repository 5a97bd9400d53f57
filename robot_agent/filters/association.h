#pragma once

#include <cstdint>
#include <vector>

#include "robot_agent/options/agent_options.h"

// Data association of one detection against one particle's landmarks (paper A's modification 2:
// on the predicted measurements), by nearest neighbour under a gate.
namespace mrslam::robot_agent::filters {

enum class AssociationKind : std::uint8_t {
  kMatched,  // within the gate of its nearest unused landmark: update it
  kNew,      // beyond the new-landmark gate of every landmark: start a landmark
  kIgnored,  // in between: too ambiguous to use either way
};

// The gates on the association distance d2 (a squared Mahalanobis distance, chi-square with 2
// degrees of freedom, or paper A's squared Euclidean distance |[dr, db]|^2):
//   Mahalanobis: match if d2 <= chi2_2(gate_probability), new if d2 > chi2_2(new_landmark_prob);
//   Euclidean:   match if d2 <= euclidean_gate^2, new otherwise (the paper's rule).
struct AssociationGates {
  bool euclidean = false;
  double match = 0.0;
  double create = 0.0;

  static AssociationGates FromOptions(const FilterOptions& options);
  AssociationKind Classify(double d2) const;
};

// Index of the smallest d2[i] over i < count with is_used(i) false (the first of equals), or -1
// if there is none.
template <typename IsUsed>
int NearestUnusedOf(const double* d2, int count, IsUsed&& is_used) {
  int best = -1;
  double best_d2 = 0.0;
  for (int i = 0; i < count; ++i) {
    if (!is_used(i) && (best < 0 || d2[i] < best_d2)) {
      best = i;
      best_d2 = d2[i];
    }
  }
  return best;
}
// The same with used[i] != 0 for a used one.
inline int NearestUnused(const double* d2, int count, const std::vector<std::uint8_t>& used) {
  return NearestUnusedOf(d2, count, [&used](int i) { return used[i] != 0; });
}

}  // namespace mrslam::robot_agent::filters
