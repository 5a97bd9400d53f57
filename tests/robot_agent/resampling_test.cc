#include "robot_agent/filters/resampling.h"

#include <cmath>
#include <numeric>

#include <gtest/gtest.h>

#include "robot_agent/filters/association.h"

namespace mrslam::robot_agent::filters {
namespace {

TEST(NormalizeLogWeights, SumsToOneAndKeepsRatios) {
  common::Rng rng(1, "normalize");
  for (int t = 0; t < 1000; ++t) {
    const int n = rng.UniformInt(1, 200);
    std::vector<double> lw(n);
    for (double& x : lw) x = rng.Uniform(-800.0, -700.0);  // far below exp's range
    const std::vector<double> before = lw;
    const std::vector<double> w = NormalizeLogWeights(&lw);
    EXPECT_NEAR(std::accumulate(w.begin(), w.end(), 0.0), 1.0, 1e-12);
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(std::exp(lw[i]), w[i], 1e-12);
      EXPECT_NEAR(lw[i] - lw[0], before[i] - before[0], 1e-9);
    }
  }
}

TEST(NormalizeLogWeights, AllImpossibleBecomesUniform) {
  std::vector<double> lw(4, -std::numeric_limits<double>::infinity());
  const std::vector<double> w = NormalizeLogWeights(&lw);
  for (const double x : w) EXPECT_DOUBLE_EQ(x, 0.25);
}

TEST(NormalizeLogWeights, UndefinedLikelihoodHasNoWeight) {
  std::vector<double> lw = {std::log(0.25), std::nan(""), std::log(0.75)};
  const std::vector<double> w = NormalizeLogWeights(&lw);
  EXPECT_NEAR(w[0], 0.25, 1e-12);
  EXPECT_EQ(w[1], 0.0);
  EXPECT_NEAR(w[2], 0.75, 1e-12);
  EXPECT_TRUE(std::isinf(lw[1]) && lw[1] < 0.0);
}

TEST(EffectiveSampleSize, EqualWeightsGiveNAndOneHotGivesOne) {
  EXPECT_NEAR(EffectiveSampleSize(std::vector<double>(100, 0.01)), 100.0, 1e-9);
  std::vector<double> one_hot(100, 0.0);
  one_hot[7] = 1.0;
  EXPECT_DOUBLE_EQ(EffectiveSampleSize(one_hot), 1.0);
}

TEST(SystematicResample, EqualWeightsKeepEveryParticle) {
  common::Rng rng(2, "resample");
  for (int t = 0; t < 1000; ++t) {
    const int n = rng.UniformInt(1, 3000);
    const std::vector<int> parents = SystematicResample(std::vector<double>(n, 1.0 / n), &rng);
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(parents[i], i) << "n = " << n;
    }
  }
}

// Low-variance resampling gives each particle floor(N w_i) or ceil(N w_i) copies.
TEST(SystematicResample, CopiesFollowWeights) {
  common::Rng rng(3, "resample");
  for (int t = 0; t < 1000; ++t) {
    const int n = rng.UniformInt(1, 500);
    std::vector<double> lw(n);
    for (double& x : lw) x = rng.Normal(0.0, 2.0);
    const std::vector<double> w = NormalizeLogWeights(&lw);
    const std::vector<int> parents = SystematicResample(w, &rng);
    ASSERT_EQ(static_cast<int>(parents.size()), n);
    std::vector<int> copies(n, 0);
    for (int i = 0; i < n; ++i) {
      if (i > 0) {
        EXPECT_LE(parents[i - 1], parents[i]);
      }
      ++copies[parents[i]];
    }
    for (int i = 0; i < n; ++i) {
      EXPECT_GE(copies[i], std::floor(n * w[i] - 1e-9));
      EXPECT_LE(copies[i], std::ceil(n * w[i] + 1e-9));
    }
  }
}

TEST(AssociationGates, MahalanobisUsesChiSquareQuantiles) {
  robot_agent::FilterOptions f;
  f.gate_probability = 0.99;
  f.new_landmark_probability = 0.999;
  const AssociationGates g = AssociationGates::FromOptions(f);
  EXPECT_NEAR(g.match, -2.0 * std::log(0.01), 1e-12);
  EXPECT_NEAR(g.create, -2.0 * std::log(0.001), 1e-12);
  EXPECT_EQ(g.Classify(1.0), AssociationKind::kMatched);
  EXPECT_EQ(g.Classify(0.5 * (g.match + g.create)), AssociationKind::kIgnored);
  EXPECT_EQ(g.Classify(g.create + 1.0), AssociationKind::kNew);
}

TEST(AssociationGates, EuclideanHasNoIgnoredBand) {
  robot_agent::FilterOptions f;
  f.association = robot_agent::Association::kEuclidean;
  f.euclidean_gate = 0.5;
  const AssociationGates g = AssociationGates::FromOptions(f);
  EXPECT_EQ(g.Classify(0.2), AssociationKind::kMatched);
  EXPECT_EQ(g.Classify(0.26), AssociationKind::kNew);
}

TEST(NearestUnused, SkipsUsedLandmarks) {
  const double d2[4] = {3.0, 1.0, 2.0, 0.5};
  EXPECT_EQ(NearestUnused(d2, 4, {0, 0, 0, 0}), 3);
  EXPECT_EQ(NearestUnused(d2, 4, {0, 0, 0, 1}), 1);
  EXPECT_EQ(NearestUnused(d2, 3, {0, 0, 0}), 1);
  EXPECT_EQ(NearestUnused(d2, 2, {1, 1}), -1);
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
