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

}  // namespace mrslam::robot_agent::filters
