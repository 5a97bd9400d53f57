#include "robot_agent/filters/landmark_ekf.h"

#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "common/rng.h"
#include "common/se2.h"

namespace mrslam::robot_agent::filters {
namespace {

constexpr int kTrials = 1000;

// A random symmetric positive definite D x D matrix with entries of order `scale`.
template <int D>
StateMatrix<D> RandomCovariance(common::Rng* rng, double scale) {
  StateMatrix<D> a;
  for (int i = 0; i < D; ++i) {
    for (int j = 0; j < D; ++j) a(i, j) = rng->Normal(0.0, std::sqrt(scale));
  }
  return a * a.transpose() + 0.1 * scale * StateMatrix<D>::Identity();
}

template <int D>
StateVector<D> RandomState(common::Rng* rng) {
  StateVector<D> x;
  for (int i = 0; i < D; ++i) x(i) = rng->Uniform(-5.0, 5.0);
  if constexpr (D > 2) x(2) = rng->Uniform(-common::kPi, common::kPi);
  if constexpr (D == 5) {
    x(3) = rng->Uniform(-1.0, 1.0);
    x(4) = rng->Uniform(-0.5, 0.5);
  }
  return x;
}

TEST(Atan2, MatchesStdAtan2ForScalarsAndLanes) {
  common::Rng rng(1, "atan2");
  for (int t = 0; t < 100000; ++t) {
    const double scale = std::pow(10.0, rng.Uniform(-6.0, 6.0));
    const double y = rng.Normal() * scale, x = rng.Normal() * scale;
    EXPECT_NEAR(Atan2(y, x), std::atan2(y, x), 4e-16 * common::kPi) << y << " " << x;
    const Double2 a = Atan2(Double2{y, x}, Double2{x, y});
    EXPECT_NEAR(a[0], std::atan2(y, x), 4e-16 * common::kPi);
    EXPECT_NEAR(a[1], std::atan2(x, y), 4e-16 * common::kPi);
  }
  EXPECT_NEAR(Atan2(0.0, 1.0), 0.0, 1e-300);
  EXPECT_NEAR(Atan2(1.0, 0.0), 0.5 * common::kPi, 1e-15);
  EXPECT_NEAR(Atan2(0.0, -1.0), common::kPi, 1e-15);
  EXPECT_NEAR(Atan2(-1.0, -1.0), -0.75 * common::kPi, 1e-15);
  EXPECT_EQ(Atan2(0.0, 0.0), 0.0);
}

// F against central differences of the motion mean, over random states.
template <int D>
void CheckMotionJacobian() {
  common::Rng rng(2, "motion_jacobian");
  constexpr double kH = 1e-6;
  for (int t = 0; t < kTrials; ++t) {
    const StateVector<D> x = RandomState<D>(&rng);
    const double v = rng.Uniform(-1.0, 1.0), w = rng.Uniform(-0.5, 0.5);
    const double dt = rng.Uniform(0.05, 1.0);
    const StateMatrix<D> f = MotionJacobian<D>(x, v, w, dt);
    for (int j = 0; j < D; ++j) {
      StateVector<D> plus = x, minus = x;
      plus(j) += kH;
      minus(j) -= kH;
      StateVector<D> diff = MotionMean<D>(plus, v, w, dt) - MotionMean<D>(minus, v, w, dt);
      if constexpr (D > 2) diff(2) = common::WrapAngle(diff(2));
      const StateVector<D> numeric = diff / (2.0 * kH);
      EXPECT_LT((numeric - f.col(j)).cwiseAbs().maxCoeff(), 1e-7) << "trial " << t << " col " << j;
    }
  }
}
TEST(MotionJacobian, UnicycleMatchesNumericDifferences) { CheckMotionJacobian<3>(); }
TEST(MotionJacobian, ConstantTurnRateMatchesNumericDifferences) { CheckMotionJacobian<5>(); }

// The lane kernel's P' equals F P F^T + Q and its mean equals the motion mean; the SSE2 block
// kernel equals the scalar one.
template <int D>
void CheckPrediction() {
  common::Rng rng(3, "prediction");
  double q[D];
  for (int i = 0; i < D; ++i) q[i] = 1e-3 * (i + 1);
  const StateMatrix<D> q_mat = Eigen::Map<StateVector<D>>(q).asDiagonal();
  for (int t = 0; t < kTrials; ++t) {
    LandmarkBlock<D> block;
    const double dt = rng.Uniform(0.05, 1.0);
    StateVector<D> means[kLanes];
    StateMatrix<D> covs[kLanes];
    double vs[kLanes], ws[kLanes];
    for (int l = 0; l < kLanes; ++l) {
      means[l] = RandomState<D>(&rng);
      covs[l] = RandomCovariance<D>(&rng, 0.1);
      vs[l] = rng.Uniform(-1.0, 1.0);
      ws[l] = rng.Uniform(-0.5, 0.5);
      block.Set(l, means[l], covs[l]);
      if constexpr (D == 3) {
        block.field[LandmarkBlock<D>::kParamV][l] = vs[l];
        block.field[LandmarkBlock<D>::kParamW][l] = ws[l];
      }
    }
    PredictBlock(&block, kLanes, dt, q);
    for (int l = 0; l < kLanes; ++l) {
      const StateMatrix<D> f = MotionJacobian<D>(means[l], vs[l], ws[l], dt);
      const StateMatrix<D> expected_cov = f * covs[l] * f.transpose() + q_mat;
      StateVector<D> mean_error = block.MeanVector(l) - MotionMean<D>(means[l], vs[l], ws[l], dt);
      if constexpr (D > 2) mean_error(2) = common::WrapAngle(mean_error(2));
      EXPECT_LT(mean_error.cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LT((block.CovMatrix(l) - expected_cov).cwiseAbs().maxCoeff(), 1e-12);
    }
  }
}
TEST(EkfPredict, StaticAddsProcessNoise) { CheckPrediction<2>(); }
TEST(EkfPredict, UnicycleMatchesEigenReference) { CheckPrediction<3>(); }
TEST(EkfPredict, ConstantTurnRateMatchesEigenReference) { CheckPrediction<5>(); }

common::Pose2 RandomPose(common::Rng* rng) {
  return {rng->Uniform(-5.0, 5.0), rng->Uniform(-5.0, 5.0), rng->Uniform(-common::kPi, common::kPi)};
}
Eigen::Vector2d RandomPointAwayFrom(const common::Pose2& pose, common::Rng* rng) {
  const double r = rng->Uniform(0.3, 8.0), a = rng->Uniform(-common::kPi, common::kPi);
  return {pose.x + r * std::cos(a), pose.y + r * std::sin(a)};
}
Eigen::Vector2d Measure(const common::Pose2& pose, const Eigen::Vector2d& point) {
  const common::RangeBearing z = common::MeasureRangeBearing(pose, point);
  return {z.range_m, z.bearing_rad};
}

TEST(MeasurementJacobian, MatchesNumericDifferences) {
  common::Rng rng(4, "measurement_jacobian");
  constexpr double kH = 1e-6;
  for (int t = 0; t < kTrials; ++t) {
    const common::Pose2 pose = RandomPose(&rng);
    const Eigen::Vector2d point = RandomPointAwayFrom(pose, &rng);
    const Eigen::Matrix2d hm = MeasurementJacobianLandmark(point, pose);
    const Eigen::Matrix<double, 2, 3> hx = MeasurementJacobianPose(point, pose);
    for (int j = 0; j < 2; ++j) {
      Eigen::Vector2d plus = point, minus = point;
      plus(j) += kH;
      minus(j) -= kH;
      Eigen::Vector2d diff = Measure(pose, plus) - Measure(pose, minus);
      diff(1) = common::WrapAngle(diff(1));
      EXPECT_LT((diff / (2 * kH) - hm.col(j)).cwiseAbs().maxCoeff(), 1e-6) << "trial " << t;
    }
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d plus = pose.Vector(), minus = pose.Vector();
      plus(j) += kH;
      minus(j) -= kH;
      Eigen::Vector2d diff =
          Measure(common::Pose2::FromVector(plus), point) - Measure(common::Pose2::FromVector(minus), point);
      diff(1) = common::WrapAngle(diff(1));
      EXPECT_LT((diff / (2 * kH) - hx.col(j)).cwiseAbs().maxCoeff(), 1e-6) << "trial " << t;
    }
  }
}

// The batch update (lanes loaded from their blocks, updated, stored back) equals the textbook
// EKF update in Eigen:
//   S = H P H^T + R, K = P H^T S^-1, x += K nu, P = (I - K H) P.
template <int D>
void CheckUpdate() {
  common::Rng rng(5, "update");
  const double var_r = 0.01, var_b = 0.001;
  const Eigen::Matrix2d r = Eigen::Vector2d(var_r, var_b).asDiagonal();
  for (int t = 0; t < kTrials / 10; ++t) {
    LandmarkBlock<D> block;
    UpdateBatch<D> batch(var_r, var_b);
    StateVector<D> means[kLanes];
    StateMatrix<D> covs[kLanes];
    common::Pose2 poses[kLanes];
    Eigen::Vector2d zs[kLanes];
    const int n = 1 + t % kLanes;  // odd sizes exercise the padding lane
    for (int l = 0; l < n; ++l) {
      poses[l] = RandomPose(&rng);
      means[l] = RandomState<D>(&rng);
      means[l].template head<2>() = RandomPointAwayFrom(poses[l], &rng);
      covs[l] = RandomCovariance<D>(&rng, 0.05);
      zs[l] = Measure(poses[l], means[l].template head<2>() + Eigen::Vector2d(rng.Normal(0, 0.2), rng.Normal(0, 0.2)));
      block.Set(l, means[l], covs[l]);
      batch.Add(&block, l, poses[l], zs[l](0), zs[l](1));
    }
    batch.Run();
    for (int l = 0; l < n; ++l) {
      Eigen::Matrix<double, 2, D> h = Eigen::Matrix<double, 2, D>::Zero();
      h.template leftCols<2>() = MeasurementJacobianLandmark(means[l].template head<2>(), poses[l]);
      const Eigen::Matrix2d s = h * covs[l] * h.transpose() + r;
      const Eigen::Matrix<double, D, 2> k = covs[l] * h.transpose() * s.inverse();
      Eigen::Vector2d nu = zs[l] - Measure(poses[l], means[l].template head<2>());
      nu(1) = common::WrapAngle(nu(1));
      const StateVector<D> mean = means[l] + k * nu;
      const StateMatrix<D> cov = (StateMatrix<D>::Identity() - k * h) * covs[l];
      EXPECT_LT((block.MeanVector(l) - mean).cwiseAbs().maxCoeff(), 1e-9) << "trial " << t;
      EXPECT_LT((block.CovMatrix(l) - 0.5 * (cov + cov.transpose())).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}
TEST(EkfUpdate, StaticMatchesEigenReference) { CheckUpdate<2>(); }
TEST(EkfUpdate, UnicycleMatchesEigenReference) { CheckUpdate<3>(); }
TEST(EkfUpdate, ConstantTurnRateMatchesEigenReference) { CheckUpdate<5>(); }

// The batch's two paths (whole blocks queued in lane order, updated row by row; single lanes,
// loaded lane by lane) give each lane exactly what EkfUpdate gives it one landmark at a time:
// whole blocks, runs cut short (lanes 0..4), lanes in reverse order, a random sample of lanes
// queued in random order between the others, over enough blocks that Add runs the batch by
// itself in the middle of a run. Lanes not queued stay as they were.
template <int D>
void CheckBatchPaths() {
  using Block = LandmarkBlock<D>;
  constexpr int kState = D + TriangleSize(D);
  common::Rng rng(7, "batch");
  const double var_r = 0.01, var_b = 0.001;
  const int num_blocks = 301;
  std::vector<Block> blocks(num_blocks);
  std::vector<common::Pose2> poses(static_cast<std::size_t>(num_blocks) * kLanes);
  std::vector<Eigen::Vector2d> zs(poses.size());
  for (int b = 0; b < num_blocks; ++b) {
    for (int l = 0; l < kLanes; ++l) {
      const int k = b * kLanes + l;
      poses[k] = RandomPose(&rng);
      StateVector<D> m = RandomState<D>(&rng);
      m.template head<2>() = RandomPointAwayFrom(poses[k], &rng);
      blocks[b].Set(l, m, RandomCovariance<D>(&rng, 0.05));
      zs[k] = Measure(poses[k], m.template head<2>() + Eigen::Vector2d(rng.Normal(0, 0.2), rng.Normal(0, 0.2)));
    }
  }
  std::vector<int> order, scattered;  // updates as block * kLanes + lane
  for (int b = 0; b < num_blocks; ++b) {
    for (int l = 0; l < kLanes; ++l) {
      const int kind = b % 4;
      const int lane = kind == 2 ? kLanes - 1 - l : l;
      if (kind == 3 || (kind == 1 && l >= 5)) {
        if (rng.Uniform() < 0.5) scattered.push_back(b * kLanes + lane);
      } else {
        order.push_back(b * kLanes + lane);
      }
    }
    if (b % 8 == 7) {  // the scattered lanes so far, shuffled, between the runs
      for (int i = static_cast<int>(scattered.size()) - 1; i > 0; --i) {
        std::swap(scattered[i], scattered[static_cast<int>(rng.Uniform() * (i + 1))]);
      }
      order.insert(order.end(), scattered.begin(), scattered.end());
      scattered.clear();
    }
  }
  std::vector<Block> expected = blocks;
  UpdateBatch<D> batch(var_r, var_b);
  for (const int k : order) {
    const int b = k / kLanes, l = k % kLanes;
    batch.Add(&blocks[b], l, poses[k], zs[k](0), zs[k](1));
    double state[kState];
    for (int f = 0; f < kState; ++f) state[f] = expected[b].field[f][l];
    EkfUpdate<double, D>(state, state + D, poses[k].x, poses[k].y, poses[k].heading, zs[k](0), zs[k](1), var_r, var_b);
    for (int f = 0; f < kState; ++f) expected[b].field[f][l] = state[f];
  }
  batch.Run();
  EXPECT_EQ(batch.size(), 0);
  for (int b = 0; b < num_blocks; ++b) {
    for (int f = 0; f < Block::kFields; ++f) {
      for (int l = 0; l < kLanes; ++l) {
        ASSERT_EQ(blocks[b].field[f][l], expected[b].field[f][l]) << "block " << b << " field " << f << " lane " << l;
      }
    }
  }
}
TEST(UpdateBatch, StaticWholeBlocksAndSingleLanesEqualOneByOne) { CheckBatchPaths<2>(); }
TEST(UpdateBatch, UnicycleWholeBlocksAndSingleLanesEqualOneByOne) { CheckBatchPaths<3>(); }
TEST(UpdateBatch, ConstantTurnRateWholeBlocksAndSingleLanesEqualOneByOne) { CheckBatchPaths<5>(); }

// The gate's squared Mahalanobis distance equals nu^T S^-1 nu with
// S = H_m P H_m^T + H_x Sigma H_x^T + R.
TEST(GateBlock, MatchesEigenReference) {
  common::Rng rng(6, "gate");
  const double var_r = 0.01, var_b = 0.001;
  const Eigen::Matrix2d r = Eigen::Vector2d(var_r, var_b).asDiagonal();
  for (int t = 0; t < kTrials; ++t) {
    const common::Pose2 pose = RandomPose(&rng);
    const Eigen::Matrix3d sigma = t % 2 ? RandomCovariance<3>(&rng, 0.01) : Eigen::Matrix3d::Zero();
    const Eigen::Vector2d z = Measure(pose, RandomPointAwayFrom(pose, &rng));
    LandmarkBlock<3> block;
    const int count = 1 + t % kLanes;
    for (int l = 0; l < count; ++l) {
      StateVector<3> m = RandomState<3>(&rng);
      m.head<2>() = RandomPointAwayFrom(pose, &rng);
      block.Set(l, m, RandomCovariance<3>(&rng, 0.05));
    }
    double d2[kLanes];
    GateBlock(block, count, pose, sigma, z(0), z(1), var_r, var_b, false, d2);
    for (int l = 0; l < kLanes; ++l) {
      if (l >= count) {
        EXPECT_TRUE(std::isinf(d2[l]));
        continue;
      }
      const Eigen::Vector2d point = block.MeanVector(l).head<2>();
      const Eigen::Matrix2d hm = MeasurementJacobianLandmark(point, pose);
      const Eigen::Matrix<double, 2, 3> hx = MeasurementJacobianPose(point, pose);
      const Eigen::Matrix2d s =
          hm * block.CovMatrix(l).topLeftCorner<2, 2>() * hm.transpose() + hx * sigma * hx.transpose() + r;
      Eigen::Vector2d nu = z - Measure(pose, point);
      nu(1) = common::WrapAngle(nu(1));
      const double expected = nu.dot(s.inverse() * nu);
      EXPECT_NEAR(d2[l], expected, 1e-9 * std::max(1.0, expected));
    }
  }
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
