#include "robot_agent/smoother/mover_memory.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.h"
#include "common/se2.h"

namespace mrslam::robot_agent::smoother {
namespace {

using filters::MapLandmark;

constexpr double kTau = 1.0;
constexpr double kGate = 9.21;  // chi-square 2 dof, 0.99

MoverMemory Memory() { return MoverMemory(kTau, Eigen::Vector3d::Zero(), 0.5); }

MapLandmark Mover(std::uint32_t track, double x, double y, double heading, std::uint32_t first, std::uint32_t last) {
  MapLandmark l;
  l.track_id = track;
  l.mean << x, y, heading;
  l.covariance = Eigen::Vector3d(0.01, 0.01, 0.01).asDiagonal();
  l.v_mps = 0.2;
  l.w_radps = 0.0;
  l.moving = true;
  l.motion = filters::LandmarkMotionKind::kConstantTurnRate;
  l.first_seen_step = first;
  l.last_seen_step = last;
  return l;
}

const MapLandmark* Find(const std::vector<MapLandmark>& map, std::uint32_t track) {
  for (const MapLandmark& l : map) {
    if (l.track_id == track) return &l;
  }
  return nullptr;
}

// The prediction's mean and spread are those of a unicycle whose velocity is a first-order
// Gauss-Markov process started at the anchor's: checked against simulated paths of that process.
TEST(MoverMemory, PredictionMatchesSimulatedGaussMarkovPaths) {
  const MoverMemory memory = Memory();
  const MapLandmark anchor = Mover(1, 0.0, 0.0, 0.0, 1, 1);
  const double t = 3.0 * kTau, dt = 0.001;
  const double sigma2 = 0.5 * anchor.v_mps * anchor.v_mps;  // per axis
  const double a = std::exp(-dt / kTau), q = std::sqrt(sigma2 * (1.0 - a * a));
  common::Rng rng(7, "mover_memory_test");
  constexpr int kPaths = 4000;
  double sx = 0.0, sxx = 0.0, syy = 0.0;
  for (int p = 0; p < kPaths; ++p) {
    double vx = anchor.v_mps, vy = 0.0, x = 0.0, y = 0.0;
    for (double s = 0.0; s < t - 0.5 * dt; s += dt) {
      x += vx * dt;
      y += vy * dt;
      vx = a * vx + q * rng.Normal(0.0, 1.0);
      vy = a * vy + q * rng.Normal(0.0, 1.0);
    }
    sx += x;
    sxx += x * x;
    syy += y * y;
  }
  const double mean_x = sx / kPaths;
  const MapLandmark predicted = memory.Predict(anchor, 10.0, 10.0 + t);
  EXPECT_NEAR(predicted.mean(0), mean_x, 0.01);
  EXPECT_NEAR(predicted.mean(0), anchor.v_mps * kTau * (1.0 - std::exp(-3.0)), 1e-12);
  EXPECT_NEAR(predicted.mean(1), 0.0, 1e-12);
  // The sample variances (4000 paths: relative sd about 2 %).
  EXPECT_NEAR(predicted.covariance(0, 0) - anchor.covariance(0, 0), sxx / kPaths - mean_x * mean_x,
              0.1 * predicted.covariance(0, 0));
  EXPECT_NEAR(predicted.covariance(1, 1) - anchor.covariance(1, 1), syy / kPaths, 0.1 * predicted.covariance(1, 1));
  // However long it goes unseen, the expected travel stays below v tau.
  EXPECT_LT(memory.Predict(anchor, 0.0, 1000.0).mean(0), anchor.v_mps * kTau + 1e-9);
}

TEST(MoverMemory, AMoverNotReadIsShownAtItsPredictionAndAReadOneAsItIs) {
  MoverMemory memory = Memory();
  memory.Remember({Mover(5, 1.0, 2.0, 0.0, 3, 10)}, 10, 5.0, kGate);
  // Ten seconds on, not read again: the front end extrapolated it 2 m along its heading.
  std::vector<MapLandmark> map = {Mover(5, 3.0, 2.0, 0.0, 3, 10)};
  memory.Remember(map, 30, 15.0, kGate);
  memory.Apply(&map, 15.0);
  ASSERT_EQ(map.size(), 1U);
  const MapLandmark expected = memory.Predict(Mover(5, 1.0, 2.0, 0.0, 3, 10), 5.0, 15.0);
  EXPECT_NEAR(map[0].mean(0), expected.mean(0), 1e-12);
  EXPECT_NEAR(map[0].mean(0), 1.0 + 0.2 * kTau * (1.0 - std::exp(-10.0)), 1e-9);
  EXPECT_GT(map[0].covariance(0, 0), 0.01);
  // Read again: shown as the estimator has it.
  map = {Mover(5, 2.5, 2.0, 0.0, 3, 31)};
  memory.Remember(map, 31, 15.5, kGate);
  memory.Apply(&map, 15.5);
  EXPECT_EQ(map[0].mean(0), 2.5);
}

// Mover 5, read last at step 10 (t = 5 s), is still held at step 30 (t = 15 s), extrapolated 2 m
// off; a static track 9 first mapped at step first_seen, read now where 5 is predicted: the map
// shown.
std::vector<MapLandmark> ShownBesideATrackFirstMappedAt(std::uint32_t first_seen) {
  MoverMemory memory = Memory();
  memory.Remember({Mover(5, 1.0, 2.0, 0.0, 3, 10)}, 10, 5.0, kGate);
  MapLandmark other = Mover(9, 1.25, 2.05, 0.0, first_seen, 30);
  other.moving = false;
  other.motion = filters::LandmarkMotionKind::kStatic;
  std::vector<MapLandmark> map = {Mover(5, 3.0, 2.0, 0.0, 3, 10), other};
  memory.Remember(map, 30, 15.0, kGate);
  memory.Apply(&map, 15.0);
  return map;
}

TEST(MoverMemory, ATrackMappedAfterAMoverWasLostWhereItIsPredictedSupersedesIt) {
  // The front end lost track 5 and maps the landmark again as track 9 (not seen moving yet).
  const std::vector<MapLandmark> map = ShownBesideATrackFirstMappedAt(28);
  ASSERT_EQ(map.size(), 1U);
  EXPECT_EQ(map[0].track_id, 9U);
}

TEST(MoverMemory, ALandmarkMappedBeforeTheMoverWasLostDoesNotSupersedeIt) {
  // Track 9 is a static landmark beside the mover's path, mapped before it was lost.
  const std::vector<MapLandmark> map = ShownBesideATrackFirstMappedAt(1);
  EXPECT_EQ(map.size(), 2U);
  ASSERT_NE(Find(map, 5), nullptr);
}

}  // namespace
}  // namespace mrslam::robot_agent::smoother
