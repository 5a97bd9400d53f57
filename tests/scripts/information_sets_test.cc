#include "scripts/batch/information_sets.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace mrslam::batch {
namespace {

// The rows s_i. (what robot i holds of every robot) after the last update.
std::vector<std::vector<int>> Held(const InformationSets& sets) {
  std::vector<std::vector<int>> out(sets.robots());
  for (int i = 0; i < sets.robots(); ++i) {
    for (int j = 0; j < sets.robots(); ++j) out[i].push_back(sets.Held(i, j));
  }
  return out;
}

// Steps 1..last with the given contacts at some steps and none at the others.
void Advance(InformationSets* sets, int first, int last,
             const std::vector<std::pair<int, std::pair<int, int>>>& contacts) {
  for (int k = first; k <= last; ++k) {
    std::vector<std::pair<int, int>> now;
    for (const auto& [step, pair] : contacts) {
      if (step == k) now.push_back(pair);
    }
    sets->Update(k, now);
  }
}

constexpr int kA = 0, kB = 1, kC = 2, kD = 3;

TEST(JointOracleSets, WithoutContactEachHoldsItsOwnDataOnly) {
  InformationSets sets(3);
  Advance(&sets, 1, 5, {});
  EXPECT_EQ(Held(sets), (std::vector<std::vector<int>>{{5, 0, 0}, {0, 5, 0}, {0, 0, 5}}));
}

TEST(JointOracleSets, AContactHandsOverTheDataUpToItAndKeepsIt) {
  InformationSets sets(3);
  Advance(&sets, 1, 9, {{4, {kA, kB}}});
  // A and B hold each other's data up to step 4; C stays alone.
  EXPECT_EQ(Held(sets), (std::vector<std::vector<int>>{{9, 4, 0}, {4, 9, 0}, {0, 0, 9}}));
}

TEST(JointOracleSets, KnowledgeTravelsThroughRobotsThatMet) {
  // A meets B at 3, B meets C at 6: A does not hold C's data yet. A meets B again at 10: A now
  // holds C's data up to 6 (through B), and C still holds A's only up to 3 (through B at 6).
  InformationSets sets(3);
  Advance(&sets, 1, 9, {{3, {kA, kB}}, {6, {kB, kC}}});
  EXPECT_EQ(sets.Held(kA, kC), 0);
  EXPECT_EQ(sets.Held(kC, kA), 3);
  EXPECT_EQ(sets.Held(kC, kB), 6);
  Advance(&sets, 10, 12, {{10, {kB, kA}}});
  EXPECT_EQ(Held(sets), (std::vector<std::vector<int>>{{12, 10, 6}, {10, 12, 6}, {3, 6, 12}}));
}

TEST(JointOracleSets, AContactPoolsTheNewestOfWhatEitherHeld) {
  // A met D at 8, B met D at 2: when A and B meet at 10 both hold D's data up to 8 (not 2).
  InformationSets sets(4);
  Advance(&sets, 1, 10, {{2, {kB, kD}}, {8, {kA, kD}}, {10, {kA, kB}}});
  EXPECT_EQ(sets.Held(kB, kD), 8);
  EXPECT_EQ(sets.Held(kA, kD), 8);
  EXPECT_EQ(sets.Held(kD, kB), 2);
  EXPECT_EQ(sets.Held(kD, kA), 8);
}

TEST(JointOracleSets, ContactsInOneStepChain) {
  // A-B and B-C at the same step: A and C did not meet, but all three hold everything up to it.
  InformationSets sets(4);
  Advance(&sets, 1, 7, {{7, {kA, kB}}, {7, {kC, kB}}});
  EXPECT_EQ(Held(sets), (std::vector<std::vector<int>>{{7, 7, 7, 0}, {7, 7, 7, 0}, {7, 7, 7, 0}, {0, 0, 0, 7}}));
}

TEST(JointOracleSets, RejectsAContactWithNoRobot) {
  InformationSets sets(2);
  EXPECT_THROW(sets.Update(1, {{0, 2}}), std::out_of_range);
  EXPECT_THROW(InformationSets(0), std::invalid_argument);
}

common::SensorStep Seeing(const std::vector<std::pair<std::string, double>>& seen_at_range) {
  common::SensorStep step;
  for (const auto& [id, range_m] : seen_at_range) step.lidar.robots.push_back({0.0, range_m, 0.1, id});
  return step;
}

TEST(JointOracleSets, ContactsAreDetectionsEitherWayFromTheStartStep) {
  const std::vector<std::string> ids = {"r1", "r2", "r3"};
  // r1 sees r2; r3 sees r2, itself, an unknown robot, and r1 at a range that is not a number.
  const std::vector<common::SensorStep> steps = {
      Seeing({{"r2", 2.0}}), Seeing({}),
      Seeing({{"r2", 1.0}, {"r3", 1.0}, {"r9", 1.0}, {"r1", std::numeric_limits<double>::quiet_NaN()}})};
  EXPECT_EQ(Contacts(steps, ids, 5, 5), (std::vector<std::pair<int, int>>{{0, 1}, {2, 1}}));
  EXPECT_TRUE(Contacts(steps, ids, 4, 5).empty());  // before rendezvous.enable_from_step
}

}  // namespace
}  // namespace mrslam::batch
