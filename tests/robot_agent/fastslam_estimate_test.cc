// FastSLAM's reported map (Estimate) against a plain computation from scratch: the same numbers
// to the bit after every step and every change of the particles or weights, over a seeded run
// with resampling, landmark removals, merges of a peer's map and observations of a known robot.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "common/angles.h"
#include "common/config/agent_options_projection.h"
#include "robot_agent/filters/fastslam.h"
#include "robot_agent/filters/map_fusion.h"
#include "tests/robot_agent/tiny_world.h"

namespace mrslam::robot_agent::filters {
namespace {

// One track's sums, as the reference below forms them.
struct Sums {
  double weight = 0.0, heading_weight = 0.0, tentative_weight = 0.0, moving_weight = 0.0;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double c = 0.0, s = 0.0, v = 0.0, v_var = 0.0, w = 0.0;
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  std::uint32_t first_seen = std::numeric_limits<std::uint32_t>::max();
  MapLandmark out;
};

// Speed, its variance and turn rate of lane l (D = 3: the known parameters, no variance).
template <int D>
Eigen::Vector3d SpeedAndTurnRate(const LandmarkBlock<D>& b, int l) {
  if constexpr (D == 5) return {b.Mean(3, l), b.Cov(3, 3, l), b.Mean(4, l)};
  if constexpr (D == 3) return {b.field[LandmarkBlock<D>::kParamV][l], 0.0, b.field[LandmarkBlock<D>::kParamW][l]};
  return Eigen::Vector3d::Zero();
}

// The map of FastSlam's class comment, computed plainly: per track id (a std::map), weighted
// sums over every particle's landmarks in particle and slot order, then the mixture covariance.
template <int D>
std::vector<MapLandmark> ReferenceMap(const FastSlam<D>& filter, int confirm_sightings) {
  std::vector<double> w(filter.NumParticles());
  double sw = 0.0;
  for (int p = 0; p < filter.NumParticles(); ++p) sw += w[p] = filter.ParticleWeight(p);
  std::map<std::uint32_t, Sums> tracks;
  const auto for_each_landmark = [&](auto&& fn) {
    for (int p = 0; p < filter.NumParticles(); ++p) {
      const std::vector<const void*> blocks = filter.LandmarkStorage(p);
      for (int s = 0; s < filter.ParticleLandmarkCount(p); ++s) {
        fn(w[p], *static_cast<const LandmarkBlock<D>*>(blocks[s / kLanes]), s % kLanes);
      }
    }
  };
  const auto has_heading = [](const LandmarkBlock<D>& b, int l) { return D > 2 && !b.meta[l].position_only; };
  for_each_landmark([&](double wp, const LandmarkBlock<D>& b, int l) {
    const LandmarkMeta& meta = b.meta[l];
    Sums& a = tracks[meta.track_id];
    a.weight += wp;
    a.xy += wp * Eigen::Vector2d(b.Mean(0, l), b.Mean(1, l));
    if (meta.sightings < confirm_sightings) a.tentative_weight += wp;
    if (!meta.stationary) a.moving_weight += wp;
    a.out.landmark_id = meta.landmark_id;
    a.out.origin_robot = meta.origin_robot;
    a.out.origin_track = meta.origin_track;
    a.out.last_seen_step = std::max(a.out.last_seen_step, meta.last_seen_step);
    a.first_seen = std::min(a.first_seen, meta.first_seen_step);
    if (has_heading(b, l)) {
      a.heading_weight += wp;
      a.c += wp * std::cos(b.Mean(2, l));
      a.s += wp * std::sin(b.Mean(2, l));
      const Eigen::Vector3d motion = SpeedAndTurnRate(b, l);
      a.v += wp * motion(0);
      a.v_var += wp * motion(1);
      a.w += wp * motion(2);
    }
  });
  for (auto& [id, a] : tracks) {
    a.out.first_seen_step = a.first_seen;
    a.out.mean.template head<2>() = a.xy / a.weight;
    a.out.mean(2) = a.heading_weight > 0.0 ? std::atan2(a.s, a.c) : 0.0;
  }
  for_each_landmark([&](double wp, const LandmarkBlock<D>& b, int l) {
    Sums& a = tracks[b.meta[l].track_id];
    const Eigen::Vector2d d(b.Mean(0, l) - a.out.mean(0), b.Mean(1, l) - a.out.mean(1));
    Eigen::Matrix2d p;
    p << b.Cov(0, 0, l), b.Cov(0, 1, l), b.Cov(0, 1, l), b.Cov(1, 1, l);
    a.second.template topLeftCorner<2, 2>() += wp * (p + d * d.transpose()) / a.weight;
    if (has_heading(b, l)) {
      const double dh = common::WrapAngle(b.Mean(2, l) - a.out.mean(2));
      const double wh = wp / a.heading_weight;
      a.second(2, 2) += wh * (b.Cov(2, 2, l) + dh * dh);
      a.second(0, 2) += wh * (b.Cov(0, 2, l) + d.x() * dh);
      a.second(1, 2) += wh * (b.Cov(1, 2, l) + d.y() * dh);
    }
  });
  std::vector<MapLandmark> map;
  for (const auto& [id, a] : tracks) {
    if (a.weight <= 0.5 * sw) continue;
    MapLandmark m = a.out;
    m.track_id = id;
    m.covariance = a.second;
    if (a.heading_weight <= 0.0) m.covariance(2, 2) = kUnknownHeadingVar;
    m.covariance(2, 0) = m.covariance(0, 2);
    m.covariance(2, 1) = m.covariance(1, 2);
    m.motion = D == 2 || a.moving_weight < 0.5 * a.weight ? LandmarkMotionKind::kStatic
               : D == 3                                   ? LandmarkMotionKind::kUnicycle
                                                          : LandmarkMotionKind::kConstantTurnRate;
    if (a.heading_weight > 0.0) {
      m.v_mps = a.v / a.heading_weight;
      m.w_radps = a.w / a.heading_weight;
      m.moving = std::abs(m.v_mps) > 2.0 * std::sqrt(a.v_var / a.heading_weight);
    }
    m.tentative = a.tentative_weight > 0.5 * a.weight;
    map.push_back(m);
  }
  return map;
}

// Every field equal, floating-point ones to the bit.
void ExpectSameMap(const std::vector<MapLandmark>& got, const std::vector<MapLandmark>& want, int step) {
  ASSERT_EQ(got.size(), want.size()) << "step " << step;
  for (std::size_t i = 0; i < got.size(); ++i) {
    const MapLandmark &a = got[i], &b = want[i];
    EXPECT_EQ(a.track_id, b.track_id) << "step " << step;
    EXPECT_EQ(a.landmark_id, b.landmark_id);
    for (int j = 0; j < 3; ++j) {
      EXPECT_EQ(a.mean(j), b.mean(j)) << "step " << step << " track " << b.track_id;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(a.covariance(j, k), b.covariance(j, k)) << "step " << step;
    }
    EXPECT_EQ(a.v_mps, b.v_mps);
    EXPECT_EQ(a.w_radps, b.w_radps);
    EXPECT_EQ(a.motion, b.motion);
    EXPECT_EQ(a.moving, b.moving);
    EXPECT_EQ(a.tentative, b.tentative);
    EXPECT_EQ(a.first_seen_step, b.first_seen_step);
    EXPECT_EQ(a.last_seen_step, b.last_seen_step);
    EXPECT_EQ(a.origin_robot, b.origin_robot);
    EXPECT_EQ(a.origin_track, b.origin_track);
  }
}

// Twelve landmarks on a ring of radius 6 m, half of them moving (constant turn rate only), the
// robot driving a circle of radius 5 m inside it with a 5 m lidar: landmarks come into view and
// leave it, tentative ones are created and dropped.
common::ScenarioOptions RingScenario(robot_agent::LandmarkKinematics kinematics) {
  common::ScenarioOptions o = testing::OneRobotScenario(1.0, 0.2, 150);
  o.robots[0].initial_pose = {0.0, -5.0, 0.0};
  o.sensors.lidar.max_range_m = 5.0;
  const bool moving = kinematics == robot_agent::LandmarkKinematics::kConstantTurnRate;
  for (int i = 0; i < 12; ++i) {
    const double a = i * common::kPi / 6.0;
    testing::AddLandmark(&o, i + 1, {6.0 * std::cos(a), 6.0 * std::sin(a), a + 0.5 * common::kPi},
                         moving && i % 2 ? 0.3 : 0.0, moving && i % 2 ? 0.05 : 0.0);
  }
  o.filter.landmark_kinematics = kinematics;
  o.filter.drop_after_misses = 2;
  return o;
}

// What the run went through, so that the comparison is known to cover it.
struct Seen {
  bool resampling = false, removal = false, merge = false, observation = false;
};

template <int D>
Seen CheckEstimateOverARun(robot_agent::LandmarkKinematics kinematics) {
  const common::ScenarioOptions o = RingScenario(kinematics);
  const int confirm = o.filter.confirm_sightings;
  testing::TinyWorld world(o, 11), peer_world(o, 12);
  FastSlam<D> filter(common::AgentOptionsFor(o, "r1"), 11), peer(common::AgentOptionsFor(o, "r1"), 12);
  Seen seen;
  std::vector<int> counts(filter.NumParticles(), 0);
  for (int k = 0; k < 80; ++k) {
    filter.Process(world.Step());
    peer.Process(peer_world.Step());
    ExpectSameMap(filter.Estimate().landmarks, ReferenceMap(filter, confirm), k);
    ExpectSameMap(filter.Estimate().landmarks, ReferenceMap(filter, confirm), k);  // kept: the same
    // Resampled: every weight 1/N; else a particle with fewer landmarks than before lost some.
    bool uniform = true;
    for (int p = 0; p < filter.NumParticles(); ++p) uniform &= filter.ParticleWeight(p) == filter.ParticleWeight(0);
    seen.resampling |= uniform;
    for (int p = 0; p < filter.NumParticles(); ++p) {
      seen.removal |= !uniform && filter.ParticleLandmarkCount(p) < counts[p];
      counts[p] = filter.ParticleLandmarkCount(p);
    }
    if (k % 10 == 9) {  // the peer's map, half of it 3 m off (new landmarks here)
      std::vector<MapLandmark> in;
      for (MapLandmark l : peer.Estimate().landmarks) {
        if (l.track_id % 2) l.mean.x() += 3.0;
        in.push_back(TransformLandmark(l, common::Pose2{}, Eigen::Vector3d(0.01, 0.01, 0.0004).asDiagonal()));
      }
      seen.merge |= filter.MergeLandmarks(in, robot_agent::MapFusionRule::kCovarianceIntersection, 0.999, 0.5) > 0;
      ExpectSameMap(filter.Estimate().landmarks, ReferenceMap(filter, confirm), k);
      for (int p = 0; p < filter.NumParticles(); ++p) counts[p] = filter.ParticleLandmarkCount(p);
    }
    if (k % 10 == 4) {  // a robot 2 m ahead of the pose estimate
      const common::Pose2 pose = filter.Estimate().pose;
      const Eigen::Vector2d ahead(pose.x + 2.0 * std::cos(pose.heading), pose.y + 2.0 * std::sin(pose.heading));
      seen.observation |= filter.ObserveKnownRobot(ahead, 0.01 * Eigen::Matrix2d::Identity(), 2.0, 0.0, 1e9);
      ExpectSameMap(filter.Estimate().landmarks, ReferenceMap(filter, confirm), k);
    }
  }
  return seen;
}

void ExpectAllSeen(const Seen& seen) {
  EXPECT_TRUE(seen.resampling);
  EXPECT_TRUE(seen.removal);
  EXPECT_TRUE(seen.merge);
  EXPECT_TRUE(seen.observation);
}

TEST(FastSlamEstimate, StaticMapEqualsTheComputationFromScratch) {
  ExpectAllSeen(CheckEstimateOverARun<2>(robot_agent::LandmarkKinematics::kStatic));
}

TEST(FastSlamEstimate, ConstantTurnRateMapEqualsTheComputationFromScratch) {
  ExpectAllSeen(CheckEstimateOverARun<5>(robot_agent::LandmarkKinematics::kConstantTurnRate));
}

}  // namespace
}  // namespace mrslam::robot_agent::filters
