#include "scripts/batch/information_sets.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace mrslam::batch {

InformationSets::InformationSets(int robots)
    : held_(static_cast<std::size_t>(robots), std::vector<int>(static_cast<std::size_t>(robots), 0)) {
  if (robots < 1) throw std::invalid_argument("a team needs at least one robot");
}

std::vector<int> InformationSets::Components(const std::vector<std::pair<int, int>>& contacts) const {
  std::vector<int> parent(held_.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const auto& [a, b] : contacts) {
    if (a < 0 || b < 0 || a >= robots() || b >= robots()) throw std::out_of_range("a contact names no robot");
    parent[root(a)] = root(b);
  }
  for (int i = 0; i < robots(); ++i) parent[i] = root(i);
  return parent;
}

void InformationSets::Update(int k, const std::vector<std::pair<int, int>>& contacts) {
  const std::vector<int> component = Components(contacts);
  const int n = robots();
  // Per component, the elementwise max of what its members held, then k for its members.
  std::vector<std::vector<int>> pooled(static_cast<std::size_t>(n), std::vector<int>(static_cast<std::size_t>(n), 0));
  for (int i = 0; i < n; ++i) {
    std::vector<int>& pool = pooled[component[i]];
    for (int j = 0; j < n; ++j) pool[j] = std::max(pool[j], held_[i][j]);
  }
  for (int i = 0; i < n; ++i) {
    held_[i] = pooled[component[i]];
    for (int j = 0; j < n; ++j) {
      if (component[j] == component[i]) held_[i][j] = k;
    }
  }
}

std::vector<std::pair<int, int>> Contacts(const std::vector<common::SensorStep>& steps,
                                          const std::vector<std::string>& ids, int k, int from_step) {
  std::vector<std::pair<int, int>> out;
  if (k < from_step) return out;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    for (const common::RobotDetection& d : steps[i].lidar.robots) {
      if (!std::isfinite(d.range_m) || !std::isfinite(d.bearing_rad)) continue;
      const auto seen = std::find(ids.begin(), ids.end(), d.seen_robot_id);
      if (seen != ids.end() && seen != ids.begin() + static_cast<std::ptrdiff_t>(i)) {
        out.emplace_back(static_cast<int>(i), static_cast<int>(seen - ids.begin()));
      }
    }
  }
  return out;
}

}  // namespace mrslam::batch
