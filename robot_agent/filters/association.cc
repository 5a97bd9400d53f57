#include "robot_agent/filters/association.h"

#include "common/gaussian.h"

namespace mrslam::robot_agent::filters {

AssociationGates AssociationGates::FromOptions(const FilterOptions& options) {
  AssociationGates g;
  g.euclidean = options.association == Association::kEuclidean;
  if (g.euclidean) {
    g.match = options.euclidean_gate * options.euclidean_gate;
    g.create = g.match;
  } else {
    g.match = common::ChiSquare2Quantile(options.gate_probability);
    g.create = common::ChiSquare2Quantile(options.new_landmark_probability);
  }
  return g;
}

AssociationKind AssociationGates::Classify(double d2) const {
  if (d2 <= match) return AssociationKind::kMatched;
  if (d2 > create) return AssociationKind::kNew;
  return AssociationKind::kIgnored;
}

int NearestUnused(const double* d2, int count, const std::vector<std::uint8_t>& used) {
  int best = -1;
  double best_d2 = 0.0;
  for (int i = 0; i < count; ++i) {
    if (used[i] == 0 && (best < 0 || d2[i] < best_d2)) {
      best = i;
      best_d2 = d2[i];
    }
  }
  return best;
}

}  // namespace mrslam::robot_agent::filters
