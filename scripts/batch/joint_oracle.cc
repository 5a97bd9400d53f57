#include "scripts/batch/joint_oracle.h"

#include <cstddef>
#include <stdexcept>

#include "scripts/batch/oracle_reference.h"

namespace mrslam::batch {

JointOracle::JointOracle(const common::ScenarioOptions& scenario,
                         const std::vector<std::pair<std::string, common::Pose2>>& frames)
    : scenario_(scenario),
      frames_(frames),
      field_statics_(FieldStatics(scenario)),
      sets_(static_cast<int>(scenario.robots.size())),
      data_(scenario.robots.size()) {
  const int n = static_cast<int>(scenario.robots.size());
  if (static_cast<int>(frames.size()) != n) throw std::invalid_argument("the joint oracle needs every robot's frame");
  for (int i = 0; i < n; ++i) {
    ids_.push_back(scenario.robots[i].id);
    Holder holder;
    holder.smoother = MakeOracleReference(scenario, field_statics_, {i}, {}, scenario.rendezvous.enable_from_step);
    holder.index.assign(static_cast<std::size_t>(n), -1);
    holder.index[i] = 0;
    robots_.push_back(std::move(holder));
  }
}

void JointOracle::Process(const std::vector<common::SensorStep>& steps, bool solve) {
  if (steps.size() != data_.size()) throw std::invalid_argument("the joint oracle needs one step per robot");
  const int k = static_cast<int>(data_.front().size()) + 1;
  for (std::size_t j = 0; j < steps.size(); ++j) data_[j].push_back(steps[j]);
  sets_.Update(k, Contacts(steps, ids_, k, scenario_.rendezvous.enable_from_step));
  for (int i = 0; i < sets_.robots(); ++i) {
    CatchUp(i);
    if (solve) robots_[i].smoother->Solve();
  }
}

void JointOracle::CatchUp(int i) {
  Holder& holder = robots_[i];
  const int n = sets_.robots();
  // New robots first, so that a detection of one in the data handed over counts.
  for (int j = 0; j < n; ++j) {
    if (holder.index[j] < 0 && sets_.Held(i, j) > 0) {
      holder.index[j] = holder.smoother->AddRobot({ids_[j], FirstPoseGuess(scenario_, frames_, i, j)});
    }
  }
  // Its own step first, then the peers' in scenario order.
  for (int offset = 0; offset < n; ++offset) {
    const int j = (i + offset) % n;
    if (holder.index[j] < 0) continue;
    const int r = holder.index[j];
    for (int t = holder.smoother->Steps(r) + 1; t <= sets_.Held(i, j); ++t) holder.smoother->Add(r, data_[j][t - 1]);
  }
}

int JointOracle::SmootherHeld(int i, int j) const {
  const Holder& holder = robots_.at(i);
  const int r = holder.index.at(j);
  return r < 0 ? 0 : holder.smoother->Steps(r);
}

}  // namespace mrslam::batch
