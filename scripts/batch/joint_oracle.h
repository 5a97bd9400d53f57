#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/config/scenario_options.h"
#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/smoother/batch_smoother.h"
#include "scripts/batch/information_sets.h"

namespace mrslam::batch {

// The causal joint oracle (mrslam_batch --reference --joint): the yardstick for robots that
// share their raw measurements when they meet. After step k robot i holds its own data of steps
// 1..k and, of every robot j, its data of steps 1..s_ij(k) (InformationSets: what contacts
// handed over, transitively); its estimate is the oracle batch MAP smoother
// (oracle_reference.h: identities, true landmark kinematics, with a landmark_field its static
// landmarks only) of exactly that data, robot i first (its first pose known, anchoring G_i), the
// others' first poses unknowns started from FirstPoseGuess, detections of each other counted
// from rendezvous.enable_from_step on (as the contacts). A robot's data only grow (s_ij never
// decreases), so each robot keeps one smoother: every step it is handed its new steps
// (BatchSmoother::Add(r, step), robots joining with AddRobot) and solved again, warm-started
// from its previous solution. Without a contact it is exactly robot i's --reference.
class JointOracle {
 public:
  // frames: the truth's frames (common::GroundTruth::frames, scenario order), for the guesses.
  JointOracle(const common::ScenarioOptions& scenario,
              const std::vector<std::pair<std::string, common::Pose2>>& frames);

  // The team's next step (steps[i]: robot i's): the contacts, every robot's data, and (solve) its
  // solve.
  void Process(const std::vector<common::SensorStep>& steps, bool solve = true);
  // Robot i's estimate (its own pose: robot 0 of the smoother), in G_i.
  const robot_agent::smoother::BatchSmoother& Of(int i) const { return *robots_.at(i).smoother; }
  const InformationSets& Sets() const { return sets_; }
  // The last step of robot j's data robot i's smoother holds (0: none); Sets().Held(i, j) after
  // every Process.
  int SmootherHeld(int i, int j) const;

 private:
  struct Holder {  // one robot's view
    std::unique_ptr<robot_agent::smoother::BatchSmoother> smoother;
    std::vector<int> index;  // scenario robot -> its index in the smoother (-1: not held)
  };
  // Hands robot i the data it now holds and not yet its smoother.
  void CatchUp(int i);

  common::ScenarioOptions scenario_;
  std::vector<std::pair<std::string, common::Pose2>> frames_;
  std::optional<std::map<int, robot_agent::smoother::BatchSmoother::Kinematics>> field_statics_;
  std::vector<std::string> ids_;
  InformationSets sets_;
  std::vector<std::vector<common::SensorStep>> data_;  // data_[j][t - 1]: robot j's step t
  std::vector<Holder> robots_;
};

}  // namespace mrslam::batch
