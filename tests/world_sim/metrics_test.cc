#include "world_sim/evaluator/metrics.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include "common/angles.h"
#include "common/se2.h"

namespace mrslam::evaluator {
namespace {

using common::kPi;
using common::Pose2;
using ::testing::ElementsAre;
using ::testing::IsEmpty;

constexpr double kTol = 1e-9;

// The frame G of the hand cases: origin at (1, 2) in the world, rotated by +90 degrees, so that
// p_G = R(-90 deg) (p_W - (1, 2)) = (y_W - 2, 1 - x_W).
const Pose2 kFrameInWorld{1.0, 2.0, kPi / 2};

// A true landmark placed at a given position in G (so the hand cases can be read in G).
TruePoint TrueAtInFrame(double x_g, double y_g, int id) {
  return {common::TransformPoint(kFrameInWorld, Eigen::Vector2d(x_g, y_g)), id};
}

MapPoint MapAt(double x_g, double y_g, int id = -1) { return {Eigen::Vector2d(x_g, y_g), id}; }

// ---------------------------------------------------------------------------------------------
// Pose errors.

// Two robots' maps of the same landmarks, each in its own frame (b's rotated by 90 degrees):
// compared in the world, through the true frames, with both covariances.
TEST(AgreementOfMapsTest, CountsTheCommonLandmarksPlacedWithinThreeSd) {
  const Pose2 frame_a{0.0, 0.0, 0.0}, frame_b{10.0, 0.0, kPi / 2};
  const auto in_b = [&](const Eigen::Vector2d& world) {
    return common::TransformPoint(common::Inverse(frame_b), world);
  };
  const auto point = [](const Eigen::Vector2d& p, double variance) {
    MapPoint m;
    m.position_m = p;
    m.covariance_m2 = variance * Eigen::Matrix2d::Identity();
    return m;
  };
  std::map<int, MapPoint> a, b;
  a[5] = point({1.0, 1.0}, 0.01);
  b[5] = point(in_b({1.3, 1.0}), 0.01);  // 0.3 m apart: d^2 = 0.09 / 0.02 = 4.5
  a[6] = point({4.0, 0.0}, 0.01);
  b[6] = point(in_b({4.0, 1.0}), 0.01);  // 1 m apart: d^2 = 50
  a[7] = point({2.0, 2.0}, 0.01);        // a's only
  a[8] = point({3.0, 3.0}, 0.0);         // no usable covariance
  b[8] = point(in_b({3.0, 3.0}), 0.01);
  const MapAgreement agreement = AgreementOfMaps(a, frame_a, b, frame_b);
  EXPECT_EQ(agreement.common, 2);
  EXPECT_EQ(agreement.within, 1);
  EXPECT_EQ(AgreementOfMaps(a, frame_a, b, frame_b, 10.0).within, 2);
}

TEST(TruthInOwnFrameTest, RotatedFrame) {
  // (1, 5, pi) in W: p_G = (5 - 2, 1 - 1) = (3, 0), heading pi - pi/2.
  const Pose2 truth = TruthInOwnFrame({1.0, 5.0, kPi}, kFrameInWorld);
  EXPECT_NEAR(truth.x, 3.0, kTol);
  EXPECT_NEAR(truth.y, 0.0, kTol);
  EXPECT_NEAR(truth.heading, kPi / 2, kTol);
}

TEST(TruthInOwnFrameTest, IdentityFrameIsTheTruth) {
  const Pose2 truth = TruthInOwnFrame({-4.0, 2.5, -1.0}, Pose2{});
  EXPECT_NEAR(truth.x, -4.0, kTol);
  EXPECT_NEAR(truth.y, 2.5, kTol);
  EXPECT_NEAR(truth.heading, -1.0, kTol);
}

TEST(PoseErrorTest, RotatedFrame) {
  const Pose2 truth = TruthInOwnFrame({1.0, 5.0, kPi}, kFrameInWorld);  // (3, 0, pi/2) in G
  const Pose2 estimate{3.3, 0.4, kPi / 2 + 0.1};
  EXPECT_NEAR(PositionError(estimate, truth), 0.5, kTol);
  EXPECT_NEAR(HeadingError(estimate, truth), 0.1, kTol);
  // The world-frame error vector (0.4, -0.3) has the same length: the norm is frame-invariant,
  // but the estimate must be compared in G, not in W.
  EXPECT_GT(PositionError(estimate, {1.0, 5.0, kPi}), 2.0);
}

TEST(PoseErrorTest, HeadingErrorIsWrappedAndAbsolute) {
  EXPECT_NEAR(HeadingError({0, 0, -kPi + 0.05}, {0, 0, kPi - 0.05}), 0.1, kTol);
  EXPECT_NEAR(HeadingError({0, 0, kPi - 0.05}, {0, 0, -kPi + 0.05}), 0.1, kTol);
  EXPECT_NEAR(HeadingError({0, 0, -0.3}, {0, 0, 0.2}), 0.5, kTol);
  EXPECT_NEAR(HeadingError({0, 0, kPi / 2}, {0, 0, -kPi / 2}), kPi, kTol);
}

// ---------------------------------------------------------------------------------------------
// NEES.

TEST(PoseNeesTest, DiagonalCovariance) {
  // e = (0.5, 2, 0.1), P = diag(0.25, 4, 0.01): 0.25/0.25 + 4/4 + 0.01/0.01 = 3.
  const Eigen::Matrix3d p = Eigen::Vector3d(0.25, 4.0, 0.01).asDiagonal();
  EXPECT_NEAR(PoseNees({1.5, 3.0, 0.6}, p, {1.0, 1.0, 0.5}), 3.0, 1e-9);
}

TEST(PoseNeesTest, HeadingDifferenceIsWrapped) {
  const Eigen::Matrix3d p = Eigen::Vector3d(1.0, 1.0, 0.01).asDiagonal();
  // e = (0, 0, 0.1) across the +-pi seam: 0.01 / 0.01 = 1.
  EXPECT_NEAR(PoseNees({0, 0, -kPi + 0.05}, p, {0, 0, kPi - 0.05}), 1.0, 1e-9);
}

TEST(PoseNeesTest, CorrelatedCovariance) {
  // P_xy = [[2, 1], [1, 2]], P_xy^-1 = [[2, -1], [-1, 2]] / 3; e = (1, 1, 0):
  // e^T P^-1 e = (2 - 1 - 1 + 2) / 3 = 2/3.
  Eigen::Matrix3d p;
  p << 2, 1, 0, 1, 2, 0, 0, 0, 1;
  EXPECT_NEAR(PoseNees({1, 1, 0}, p, {0, 0, 0}), 2.0 / 3.0, 1e-12);
}

TEST(PoseNeesTest, NotPositiveDefiniteIsNan) {
  Eigen::Matrix3d p;
  p << 1, 2, 0, 2, 1, 0, 0, 0, 1;  // eigenvalues -1, 3, 1
  EXPECT_TRUE(std::isnan(PoseNees({1, 0, 0}, p, {0, 0, 0})));
}

// ---------------------------------------------------------------------------------------------
// Hungarian assignment.

double AssignmentCost(const Eigen::MatrixXd& cost, const std::vector<int>& row_to_col) {
  double total = 0.0;
  for (size_t r = 0; r < row_to_col.size(); ++r) {
    if (row_to_col[r] >= 0) total += cost(static_cast<Eigen::Index>(r), row_to_col[r]);
  }
  return total;
}

// Checks that the assignment is one-to-one and covers min(rows, cols) pairs.
void ExpectValidAssignment(const Eigen::MatrixXd& cost, const std::vector<int>& row_to_col) {
  ASSERT_EQ(row_to_col.size(), static_cast<size_t>(cost.rows()));
  std::vector<bool> used(static_cast<size_t>(cost.cols()), false);
  int assigned = 0;
  for (const int c : row_to_col) {
    if (c < 0) continue;
    ASSERT_LT(c, cost.cols());
    EXPECT_FALSE(used[c]) << "column " << c << " assigned twice";
    used[c] = true;
    ++assigned;
  }
  EXPECT_EQ(assigned, std::min(cost.rows(), cost.cols()));
}

// Minimum over every injective map of the shorter side into the longer one.
double BruteForceMinCost(const Eigen::MatrixXd& cost) {
  const Eigen::MatrixXd a = cost.rows() <= cost.cols() ? cost : Eigen::MatrixXd(cost.transpose());
  std::vector<int> cols(static_cast<size_t>(a.cols()));
  std::iota(cols.begin(), cols.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double total = 0.0;
    for (Eigen::Index r = 0; r < a.rows(); ++r) total += a(r, cols[r]);
    best = std::min(best, total);
  } while (std::next_permutation(cols.begin(), cols.end()));
  return best;
}

TEST(OptimalAssignmentTest, BeatsGreedySquare) {
  // Greedy takes (0,0) = 1 and is left with (1,1) = 100; the optimum is 2 + 2.
  Eigen::MatrixXd cost(2, 2);
  cost << 1, 2, 2, 100;
  EXPECT_THAT(OptimalAssignment(cost), ElementsAre(1, 0));
}

TEST(OptimalAssignmentTest, BeatsGreedyThreeByThree) {
  // Row-wise greedy: 0->0 (1), 1->1 (3), 2->2 (9) = 13. Optimum: 0->1 (2) + 1->2 (4) + 2->0 (2).
  Eigen::MatrixXd cost(3, 3);
  cost << 1, 2, 5,  //
      4, 3, 4,      //
      2, 6, 9;
  const std::vector<int> assignment = OptimalAssignment(cost);
  EXPECT_THAT(assignment, ElementsAre(1, 2, 0));
  EXPECT_DOUBLE_EQ(AssignmentCost(cost, assignment), 8.0);
}

TEST(OptimalAssignmentTest, WideMatrix) {
  Eigen::MatrixXd cost(2, 3);
  cost << 1, 2, 3,  //
      2, 100, 100;
  EXPECT_THAT(OptimalAssignment(cost), ElementsAre(1, 0));
}

TEST(OptimalAssignmentTest, TallMatrixLeavesRowsUnassigned) {
  Eigen::MatrixXd cost(3, 2);
  cost << 1, 2,  //
      2, 100,    //
      3, 100;
  EXPECT_THAT(OptimalAssignment(cost), ElementsAre(1, 0, -1));
}

TEST(OptimalAssignmentTest, NegativeCosts) {
  Eigen::MatrixXd cost(2, 2);
  cost << -1, -2, -2, -100;
  EXPECT_THAT(OptimalAssignment(cost), ElementsAre(0, 1));
}

TEST(OptimalAssignmentTest, EmptyMatrices) {
  EXPECT_THAT(OptimalAssignment(Eigen::MatrixXd(0, 0)), IsEmpty());
  EXPECT_THAT(OptimalAssignment(Eigen::MatrixXd(0, 3)), IsEmpty());
  EXPECT_THAT(OptimalAssignment(Eigen::MatrixXd(3, 0)), ElementsAre(-1, -1, -1));
}

// Property test: 200 seeded random matrices of each shape against brute force, with real-valued
// costs and with small integer costs (many ties).
class OptimalAssignmentRandomTest : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(OptimalAssignmentRandomTest, MatchesBruteForce) {
  const auto [rows, cols] = GetParam();
  std::mt19937 rng(12345u + static_cast<unsigned>(rows * 10 + cols));
  std::uniform_real_distribution<double> real_cost(0.0, 10.0);
  std::uniform_int_distribution<int> int_cost(0, 3);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::MatrixXd cost(rows, cols);
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        cost(r, c) = trial % 2 == 0 ? real_cost(rng) : static_cast<double>(int_cost(rng));
      }
    }
    const std::vector<int> assignment = OptimalAssignment(cost);
    ExpectValidAssignment(cost, assignment);
    EXPECT_NEAR(AssignmentCost(cost, assignment), BruteForceMinCost(cost), 1e-9) << "trial " << trial << "\n" << cost;
  }
}

INSTANTIATE_TEST_SUITE_P(Shapes, OptimalAssignmentRandomTest,
                         ::testing::Values(std::make_pair(5, 5), std::make_pair(4, 6), std::make_pair(6, 4),
                                           std::make_pair(1, 5), std::make_pair(7, 7)));

// ---------------------------------------------------------------------------------------------
// Landmark errors.

TEST(LandmarkErrorsTest, ByIdentityInRotatedFrame) {
  const std::vector<TruePoint> truth = {TrueAtInFrame(3.0, 0.0, 7), TrueAtInFrame(0.0, 2.0, 8)};
  // Hand check of the frame change for the first one: (1, 5) in W is (3, 0) in G.
  ASSERT_NEAR(truth[0].position_m.x(), 1.0, kTol);
  ASSERT_NEAR(truth[0].position_m.y(), 5.0, kTol);
  const std::vector<MapPoint> map = {MapAt(0.0, 2.2, 8), MapAt(3.3, 0.4, 7)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld),
              ElementsAre(::testing::DoubleNear(0.2, kTol), ::testing::DoubleNear(0.5, kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(0, 1));
}

TEST(LandmarkErrorsTest, IdentityWinsOverProximity) {
  const std::vector<TruePoint> truth = {TrueAtInFrame(3.0, 0.0, 7), TrueAtInFrame(0.0, 2.0, 8)};
  // Sits on landmark 7 but says it is 8: error |(3, 0) - (0, 2)| = sqrt(13) with a wide cut-off.
  const std::vector<MapPoint> map = {MapAt(3.0, 0.0, 8)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld, 10.0),
              ElementsAre(::testing::DoubleNear(std::sqrt(13.0), kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld, 10.0), ElementsAre(1));
  // With the default 3 m cut-off it is too far: counts 3 m, matches nothing, and landmark 7 stays
  // claimed by identity (not offered to the assignment).
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld), ElementsAre(3.0));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), IsEmpty());
}

TEST(LandmarkErrorsTest, UnknownIdentityIsAssigned) {
  const std::vector<TruePoint> truth = {TrueAtInFrame(3.0, 0.0, 7), TrueAtInFrame(0.0, 2.0, 8)};
  // Id 42 does not exist in the truth: assigned like an unidentified landmark, to the free one.
  const std::vector<MapPoint> map = {MapAt(3.0, 0.3, 42), MapAt(0.0, 2.4, 8)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld),
              ElementsAre(::testing::DoubleNear(0.3, kTol), ::testing::DoubleNear(0.4, kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(0, 1));
}

TEST(LandmarkErrorsTest, WithoutIdentitiesCrossing) {
  // True T0 = (0, 0), T1 = (2, 0); map m0 = (1.1, 0) is nearer T1 (0.9) than T0 (1.1), and
  // m1 = (3.5, 0) is 1.5 from T1 and 3.5 from T0. Nearest-first greedy gives m0 -> T1 and leaves
  // m1 with T0 beyond the cut-off: errors (0.9, 3). The optimum crosses: m0 -> T0 and m1 -> T1,
  // sum of squares 1.21 + 2.25 = 3.46 < 0.81 + 9.
  const std::vector<TruePoint> truth = {TrueAtInFrame(0.0, 0.0, 0), TrueAtInFrame(2.0, 0.0, 1)};
  const std::vector<MapPoint> map = {MapAt(1.1, 0.0), MapAt(3.5, 0.0)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld),
              ElementsAre(::testing::DoubleNear(1.1, kTol), ::testing::DoubleNear(1.5, kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(0, 1));
}

TEST(LandmarkErrorsTest, GhostBeyondCutoffCountsCutoff) {
  const std::vector<TruePoint> truth = {TrueAtInFrame(0.0, 0.0, 0), TrueAtInFrame(2.0, 0.0, 1)};
  const std::vector<MapPoint> map = {MapAt(0.1, 0.0), MapAt(20.0, 0.0), MapAt(2.0, 0.2)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld),
              ElementsAre(::testing::DoubleNear(0.1, kTol), 3.0, ::testing::DoubleNear(0.2, kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(0, 1));
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld, 5.0),
              ElementsAre(::testing::DoubleNear(0.1, kTol), 5.0, ::testing::DoubleNear(0.2, kTol)));
}

TEST(LandmarkErrorsTest, FarGhostDoesNotStealPartner) {
  // T0 = (0, 0), T1 = (10, 0); m0 = (0.5, 0) by T0, ghost m1 = (-5, 0) far from both. Unclipped
  // squared distances would prefer m0 -> T1, m1 -> T0 (90.25 + 25 < 0.25 + 225); with costs
  // capped at the cut-off m0 keeps T0: errors (0.5, 3).
  const std::vector<TruePoint> truth = {TrueAtInFrame(0.0, 0.0, 0), TrueAtInFrame(10.0, 0.0, 1)};
  const std::vector<MapPoint> map = {MapAt(0.5, 0.0), MapAt(-5.0, 0.0)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld), ElementsAre(::testing::DoubleNear(0.5, kTol), 3.0));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(0));
}

TEST(LandmarkErrorsTest, MoreTruthThanMapAndEmptyInputs) {
  const std::vector<TruePoint> truth = {TrueAtInFrame(0.0, 0.0, 0), TrueAtInFrame(2.0, 0.0, 1),
                                        TrueAtInFrame(4.0, 0.0, 2)};
  const std::vector<MapPoint> map = {MapAt(3.8, 0.0)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld), ElementsAre(::testing::DoubleNear(0.2, kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(2));
  EXPECT_THAT(LandmarkErrors({}, truth, kFrameInWorld), IsEmpty());
  EXPECT_THAT(MatchedTruth({}, truth, kFrameInWorld), IsEmpty());
  EXPECT_THAT(LandmarkErrors(map, {}, kFrameInWorld), ElementsAre(3.0));
  EXPECT_THAT(MatchedTruth(map, {}, kFrameInWorld), IsEmpty());
}

TEST(LandmarkErrorsTest, DuplicateIdentitiesBothMeasuredAgainstTheirLandmark) {
  const std::vector<TruePoint> truth = {TrueAtInFrame(0.0, 0.0, 5), TrueAtInFrame(2.0, 0.0, 6)};
  const std::vector<MapPoint> map = {MapAt(0.1, 0.0, 5), MapAt(-0.3, 0.0, 5)};
  EXPECT_THAT(LandmarkErrors(map, truth, kFrameInWorld),
              ElementsAre(::testing::DoubleNear(0.1, kTol), ::testing::DoubleNear(0.3, kTol)));
  EXPECT_THAT(MatchedTruth(map, truth, kFrameInWorld), ElementsAre(0));
}

// ---------------------------------------------------------------------------------------------
// Statistics.

TEST(StatisticsTest, Rmse) {
  EXPECT_NEAR(Rmse({3.0, 4.0}), std::sqrt(12.5), kTol);
  EXPECT_NEAR(Rmse({-2.0}), 2.0, kTol);
  EXPECT_EQ(Rmse({}), 0.0);
}

TEST(StatisticsTest, Median) {
  EXPECT_DOUBLE_EQ(Median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(Median({7.0}), 7.0);
  EXPECT_TRUE(std::isnan(Median({})));
}

TEST(StatisticsTest, PercentileInterpolatesLikeNumpy) {
  // numpy.percentile([1, 2, 3, 4, 5], 90) = 4.6 (rank 3.6); [10, 20] at 25 -> 12.5.
  EXPECT_NEAR(Percentile({5.0, 1.0, 4.0, 2.0, 3.0}, 90.0), 4.6, kTol);
  EXPECT_NEAR(Percentile({20.0, 10.0}, 25.0), 12.5, kTol);
  EXPECT_DOUBLE_EQ(Percentile({5.0, 1.0, 4.0, 2.0, 3.0}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Percentile({5.0, 1.0, 4.0, 2.0, 3.0}, 100.0), 5.0);
  EXPECT_DOUBLE_EQ(Percentile({5.0, 1.0, 4.0, 2.0, 3.0}, 50.0), 3.0);
  // numpy.percentile([0, 1, 10], 75) = 5.5 (rank 1.5).
  EXPECT_NEAR(Percentile({10.0, 0.0, 1.0}, 75.0), 5.5, kTol);
  EXPECT_DOUBLE_EQ(Percentile({2.0}, 90.0), 2.0);
  EXPECT_TRUE(std::isnan(Percentile({}, 90.0)));
}

// ---------------------------------------------------------------------------------------------
// Frame transforms.

// G_i at (1, 2, pi/2), G_j at (4, -1, -pi/2) in W. The origin of G_j in G_i:
// R(-90 deg) ((4, -1) - (1, 2)) = R(-90 deg) (3, -3) = (-3, -3); heading -pi/2 - pi/2 = pi.
const Pose2 kFrameJInWorld{4.0, -1.0, -kPi / 2};

TEST(FrameTransformErrorTest, ZeroForTheTrueTransform) {
  const TransformError error = FrameTransformError({-3.0, -3.0, kPi}, kFrameInWorld, kFrameJInWorld);
  EXPECT_NEAR(error.translation_m, 0.0, kTol);
  EXPECT_NEAR(error.rotation_rad, 0.0, kTol);
  // Also for the true transform as Between computes it, and with -pi for pi.
  const TransformError between =
      FrameTransformError(common::Between(kFrameInWorld, kFrameJInWorld), kFrameInWorld, kFrameJInWorld);
  EXPECT_NEAR(between.translation_m, 0.0, kTol);
  EXPECT_NEAR(between.rotation_rad, 0.0, kTol);
  EXPECT_NEAR(FrameTransformError({-3.0, -3.0, -kPi}, kFrameInWorld, kFrameJInWorld).rotation_rad, 0.0, kTol);
}

TEST(FrameTransformErrorTest, PerturbedTransform) {
  // (-2.7, -3.4) is (0.3, -0.4) away in G_i: 0.5 m; heading -pi + 0.05 is 0.05 from pi.
  const TransformError error = FrameTransformError({-2.7, -3.4, -kPi + 0.05}, kFrameInWorld, kFrameJInWorld);
  EXPECT_NEAR(error.translation_m, 0.5, kTol);
  EXPECT_NEAR(error.rotation_rad, 0.05, kTol);
}

TEST(FrameTransformErrorTest, RandomTrueTransformsGiveZero) {
  std::mt19937 rng(7u);
  std::uniform_real_distribution<double> xy(-50.0, 50.0), angle(-kPi, kPi);
  for (int trial = 0; trial < 200; ++trial) {
    const Pose2 i{xy(rng), xy(rng), angle(rng)}, j{xy(rng), xy(rng), angle(rng)};
    // T(G_i <- G_j) maps a point given in G_j to the same world point as G_j does.
    const Pose2 t_i_j = common::Compose(common::Inverse(i), j);
    const Eigen::Vector2d p_j(xy(rng), xy(rng));
    EXPECT_LT((common::TransformPoint(i, common::TransformPoint(t_i_j, p_j)) - common::TransformPoint(j, p_j)).norm(),
              1e-9);
    const TransformError error = FrameTransformError(t_i_j, i, j);
    EXPECT_LT(error.translation_m, 1e-9);
    EXPECT_LT(error.rotation_rad, 1e-9);
  }
}

}  // namespace
}  // namespace mrslam::evaluator
