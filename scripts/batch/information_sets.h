#pragma once

#include <string>
#include <utility>
#include <vector>

#include "common/sensor_types.h"

namespace mrslam::batch {

// What each robot of a team holds of the team's data as the run goes on, if robots that meet
// hand each other everything they hold (the causal joint oracle's bookkeeping, joint_oracle.h).
// held(i, j) = s_ij(k): the last step of robot j's sensor data that robot i holds after step k
// (0: none; steps count from 1). After step k:
//   s_ii(k) = k;
//   robots in contact at step k form a graph; for every connected component C of it and every
//   i in C, s_ij(k) = max over m in C of s_mj(k - 1) for robots j outside C, and s_ij(k) = k for
//   j in C (a contact hands over the partner's data up to k and everything it holds, and that
//   travels along chains of contacts within the step too: the fixed point of the pairwise rule);
//   a robot in no contact keeps what it held.
// Knowledge therefore travels transitively through robots that met: if A meets B at step 10 and
// B met C at step 4, A holds C's data up to 4 from step 10 on. Pure.
class InformationSets {
 public:
  explicit InformationSets(int robots);

  // Step k's contacts (pairs of robot indices; order and repeats do not matter). Steps must come
  // in order, one call each.
  void Update(int k, const std::vector<std::pair<int, int>>& contacts);
  // s_ij after the last Update.
  int Held(int i, int j) const { return held_.at(i).at(j); }
  int robots() const { return static_cast<int>(held_.size()); }

 private:
  // The connected components' representative of each robot under the contacts (union-find).
  std::vector<int> Components(const std::vector<std::pair<int, int>>& contacts) const;

  std::vector<std::vector<int>> held_;
};

// Step k's contacts of a team from its sensor data (steps[i]: robot i's, ids[i] its scenario
// id): i and j are in contact when either one's lidar detects the other (a finite range and
// bearing naming it), from step from_step on (rendezvous.enable_from_step: before it the agents
// do not cooperate and the joint reference does not count detections of each other).
std::vector<std::pair<int, int>> Contacts(const std::vector<common::SensorStep>& steps,
                                          const std::vector<std::string>& ids, int k, int from_step);

}  // namespace mrslam::batch
