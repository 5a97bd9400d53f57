#include "robot_agent/filters/fastslam.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "common/gaussian.h"
#include "robot_agent/filters/map_fusion.h"
#include "robot_agent/filters/resampling.h"

namespace mrslam::robot_agent::filters {
namespace {

using common::kPi;
using common::Pose2;
using common::WrapAngle;

// How far a particle's proposal may move (FastSLAM 2.0: with each matched reading) before the
// landmarks its readings can gate are gathered again: a step's corrections are centimetres.
constexpr double kReachShiftM = 0.25;

// Largest landmark speed the filter may meet: the fastest known candidate, else the bound.
double MaxLandmarkSpeed(const FilterOptions& f) {
  if (f.landmark_kinematics == LandmarkKinematics::kKnownCandidates) {
    double s = 0.0;
    for (const auto& k : f.known_kinematics) s = std::max(s, std::abs(k.v_mps));
    return s;
  }
  return f.landmark_kinematics == LandmarkKinematics::kStatic ? 0.0 : f.max_landmark_speed_mps;
}

// Length of the chord travelled in n unicycle steps of v dt turning w dt each:
//   |sum_k v dt e^{i k w dt}| = v dt |sin(n w dt / 2) / sin(w dt / 2)|.
double ChordLength(double v, double w, double dt, int n) {
  const double half = 0.5 * w * dt;
  if (std::abs(half) < 1e-9) return std::abs(v) * dt * n;
  return std::abs(v * dt * std::sin(n * half) / std::sin(half));
}

// Whether a peer landmark's heading is worth fusing: a state with one, and the peer's known better
// than half the uniform variance.
template <int D>
bool PeerHeadingKnown(const MapLandmark& peer) {
  return D > 2 && peer.covariance(2, 2) < 0.5 * kUnknownHeadingVar;
}

// Accessors that exist for some state dimensions only: speed, turn rate and heading (variance
// and covariances with x, y) of lane l. Static landmarks have none.
template <int D>
double SpeedOf(const LandmarkBlock<D>& b, int l) {
  if constexpr (D == 5) return b.Mean(3, l);
  if constexpr (D == 3) return b.field[LandmarkBlock<D>::kParamV][l];
  return 0.0;
}
template <int D>
double SpeedVarOf(const LandmarkBlock<D>& b, int l) {
  if constexpr (D == 5) return b.Cov(3, 3, l);
  return 0.0;
}
template <int D>
double TurnRateOf(const LandmarkBlock<D>& b, int l) {
  if constexpr (D == 5) return b.Mean(4, l);
  if constexpr (D == 3) return b.field[LandmarkBlock<D>::kParamW][l];
  return 0.0;
}
template <int D>
double HeadingOf(const LandmarkBlock<D>& b, int l) {
  if constexpr (D > 2) return b.Mean(2, l);
  return 0.0;
}
template <int D>
double HeadingCovOf(const LandmarkBlock<D>& b, int i, int l) {  // cov(i, heading)
  if constexpr (D > 2) return b.Cov(i, 2, l);
  return 0.0;
}

// One track's weighted sums over the particles that hold it (FastSlam::MapEstimate).
struct TrackAccumulator {
  std::uint32_t id = 0;
  double weight = 0.0, heading_weight = 0.0, tentative_weight = 0.0, moving_weight = 0.0;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double c = 0.0, s = 0.0, v = 0.0, v_var = 0.0, w = 0.0;
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  std::uint32_t first_seen = std::numeric_limits<std::uint32_t>::max();
  MapLandmark out;
};

// The map's landmark of track id from its accumulated sums, for a state of dimension dim.
MapLandmark TrackLandmark(std::uint32_t id, const TrackAccumulator& a, int dim) {
  MapLandmark m = a.out;
  m.track_id = id;
  m.covariance = a.second;
  if (a.heading_weight <= 0.0) m.covariance(2, 2) = kUnknownHeadingVar;
  m.covariance(2, 0) = m.covariance(0, 2);
  m.covariance(2, 1) = m.covariance(1, 2);
  // Constant turn rate: static when the particles that take it as static carry more than
  // half of its holders' weight.
  m.motion = dim == 2 || a.moving_weight < 0.5 * a.weight ? LandmarkMotionKind::kStatic
             : dim == 3                                   ? LandmarkMotionKind::kUnicycle
                                                          : LandmarkMotionKind::kConstantTurnRate;
  if (a.heading_weight > 0.0) {
    m.v_mps = a.v / a.heading_weight;
    m.w_radps = a.w / a.heading_weight;
    // Known models move when their speed is not zero; an estimated speed must stand out of
    // its own uncertainty (two standard deviations).
    const double v_sd = std::sqrt(a.v_var / a.heading_weight);
    m.moving = std::abs(m.v_mps) > 2.0 * v_sd;
  }
  m.tentative = a.tentative_weight > 0.5 * a.weight;
  return m;
}

// The accumulators of MapEstimate, one per track id in the order first met (tracks()), and
// which one a landmark adds to. Visited particle after particle, slot after slot, a landmark's
// track is mostly the one the previous particle holds at the same slot (the particles descend
// from few ancestors); it is looked up by id only when that differs.
class TrackTable {
 public:
  // The index in tracks() of the track of the landmark with track id `id` at `slot`.
  int Find(int slot, std::uint32_t id) {
    if (static_cast<int>(at_slot_.size()) <= slot) at_slot_.resize(slot + 1, -1);
    int& t = at_slot_[slot];
    if (t < 0 || tracks_[t].id != id) t = Lookup(id);
    return t;
  }
  std::vector<TrackAccumulator>& tracks() { return tracks_; }

 private:
  // The track of id, added if new (the rare path: kept out of the visiting loops).
  __attribute__((noinline)) int Lookup(std::uint32_t id) {
    const auto [it, added] = by_id_.try_emplace(id, static_cast<int>(tracks_.size()));
    if (added) tracks_.emplace_back().id = id;
    return it->second;
  }

  std::vector<TrackAccumulator> tracks_;
  std::map<std::uint32_t, int> by_id_;
  std::vector<int> at_slot_;  // per slot, the track of the last landmark found there
};

}  // namespace

template <int D>
FastSlam<D>::FastSlam(const AgentOptions& options, std::uint64_t seed)
    : filter_(options.filter),
      lidar_(options.sensors.lidar),
      imu_(options.sensors.imu),
      noise_(options.noise),
      odometry_var_(options.sensors.odometry.v_noise_sd_mps * options.sensors.odometry.v_noise_sd_mps,
                    options.sensors.odometry.w_noise_sd_radps * options.sensors.odometry.w_noise_sd_radps),
      step_dt_s_(options.dt_s),
      gates_(AssociationGates::FromOptions(options.filter)),
      fastslam2_(options.filter.proposal == Proposal::kMeasurement),
      robot_index_(options.TeamIndex(options.robot_id)),
      var_r_(lidar_.range_noise_sd_m * lidar_.range_noise_sd_m),
      var_b_(lidar_.bearing_noise_sd_rad * lidar_.bearing_noise_sd_rad),
      log_new_d2_(common::ChiSquare2Quantile(options.filter.new_landmark_probability)),
      max_position_var_(options.filter.max_landmark_position_sd_m * options.filter.max_landmark_position_sd_m),
      batch_(var_r_, var_b_),
      rng_(seed, options.robot_id + "/fastslam"),
      last_ess_(options.filter.particles),
      calibration_(options.filter),
      reachable_(ReachRule{std::max(gates_.match, gates_.create), var_r_, var_b_, gates_.euclidean, kReachShiftM}) {
  // Landmark process noise per step: none for static landmarks; (x, y, heading) from the
  // scenario, and for constant turn rate the speed and turn-rate random walks.
  for (int i = 0; i < D; ++i) q_[i] = 0.0;
  if constexpr (D >= 3) {
    for (int i = 0; i < 3; ++i) q_[i] = noise_.landmark_process_var(i);
  }
  if constexpr (D == 5) {
    q_[3] = filter_.landmark_speed_process_var;
    q_[4] = filter_.landmark_turn_rate_process_var;
  }
  const double s_max_step = MaxLandmarkSpeed(filter_) * step_dt_s_;
  unknown_heading_inflation_ = 0.5 * s_max_step * s_max_step;

  const Pose2 start = options.initial_pose;
  const int n = std::max(1, filter_.particles);
  particles_.assign(n, Particle{start, 0.0, 0, 0, {}});
  log_weights_.assign(n, -std::log(static_cast<double>(n)));
  pose_ = start;
  pose_covariance_.setZero();
}

template <int D>
double FastSlam<D>::ParticleWeight(int i) const {
  return std::exp(log_weights_[i]);
}

template <int D>
std::vector<const void*> FastSlam<D>::LandmarkStorage(int i) const {
  std::vector<const void*> out;
  for (const auto& b : particles_[i].blocks) out.push_back(b.get());
  return out;
}

// The object, each particle and its block pointers, each distinct landmark block once (shared
// copies as the archive writes them), the weights and the step's labels.
template <int D>
std::size_t FastSlam<D>::EstimatorBytes() const {
  std::vector<const Block*> blocks;
  std::size_t bytes = sizeof(*this) + ElementBytes(particles_) + ElementBytes(log_weights_) +
                      ElementBytes(creation_ids_) + ElementBytes(detection_labels_) + ElementBytes(detection_tracks_);
  for (const Particle& p : particles_) {
    bytes += ElementBytes(p.blocks);
    for (const auto& b : p.blocks) blocks.push_back(b.get());
  }
  std::sort(blocks.begin(), blocks.end());
  const auto distinct = static_cast<std::size_t>(std::unique(blocks.begin(), blocks.end()) - blocks.begin());
  return bytes + distinct * sizeof(Block);
}

template <int D>
void FastSlam<D>::MotionFromStep(const common::SensorStep& step, std::vector<Segment>* segments,
                                 Eigen::Vector3d* variance) {
  segments->clear();
  *variance = noise_.robot_process_var;
  imu_step_ = filter_.motion_source == MotionSource::kImu && !step.imu.readings.empty();
  if (imu_step_) {
    // w = mean gyro rate; the speed is part of each particle's state (the robot starts at rest):
    //   v_p += mean(accel_x) dt + N(0, sd_a^2 dt^2 / n),
    // so the weights select the speeds the landmarks agree with; a speed integrated once for all
    // particles would drift without bound. The gyro noise adds sd_g^2 dt^2 / n to the heading.
    const int n = static_cast<int>(step.imu.readings.size());
    double gyro = 0.0, accel = 0.0;
    for (const auto& r : step.imu.readings) {
      gyro += r.gyro_z_radps;
      accel += r.accel_x_mps2;
    }
    const double dt = step_dt_s_;
    imu_speed_change_ = accel / n * dt;
    imu_speed_var_ = imu_.accel_noise_sd_mps2 * imu_.accel_noise_sd_mps2 * dt * dt / n;
    segments->push_back({0.0, gyro / n, dt});
    (*variance)(2) += imu_.gyro_noise_sd_radps * imu_.gyro_noise_sd_radps * dt * dt / n;
    return;
  }
  *segments = calibration_.Step(step.odometry, time_s_, step_dt_s_);
}

template <int D>
void FastSlam<D>::Process(const common::SensorStep& step) {
  map_estimate_.value.reset();
  step_ = step.lidar.stamp.step;
  time_s_ = step.lidar.stamp.time_s;
  std::vector<Segment> segments;
  Eigen::Vector3d var;
  MotionFromStep(step, &segments, &var);
  double dt = 0.0;
  for (const auto& s : segments) dt += s.dt_s;

  // Valid detections sorted by (range, bearing, id): the result does not depend on the order
  // in which the scan lists them.
  std::vector<Detection> detections;
  const int scanned = static_cast<int>(step.lidar.landmarks.size());
  for (int i = 0; i < scanned; ++i) {
    const auto& d = step.lidar.landmarks[i];
    if (std::isfinite(d.range_m) && std::isfinite(d.bearing_rad) && d.range_m > 0.0) {
      detections.push_back({d.range_m, WrapAngle(d.bearing_rad), d.landmark_id, 0, i});
    }
  }
  std::sort(detections.begin(), detections.end(), [](const Detection& a, const Detection& b) {
    return std::tie(a.range_m, a.bearing_rad, a.landmark_id) < std::tie(b.range_m, b.bearing_rad, b.landmark_id);
  });
  for (int i = 0; i < static_cast<int>(detections.size()); ++i) detections[i].index = i;
  creation_ids_.assign(detections.size(), 0);
  if (!detections.empty()) reachable_.StartStep(detections.front().range_m, detections.back().range_m);
  detection_labels_.assign(detections.size() * particles_.size(), 0);

  for (int p = 0; p < NumParticles(); ++p) {
    ProposeParticle(p, segments, var, dt, detections, &batch_);
  }
  batch_.Run();
  for (int p = 0; p < NumParticles(); ++p) {
    CountMisses(p);
    if constexpr (D == 5) GatherStationary(&particles_[p]);
  }

  const std::vector<double> weights = NormalizeLogWeights(&log_weights_);
  last_ess_ = EffectiveSampleSize(weights);
  const std::size_t best = static_cast<std::size_t>(std::max_element(weights.begin(), weights.end()) - weights.begin());
  detection_tracks_.assign(scanned, 0);
  for (const Detection& det : detections) {
    detection_tracks_[det.scan_index] = detection_labels_[best * detections.size() + det.index];
  }
  // The pose estimate comes from the weighted particles, before resampling adds its noise.
  EstimatePose(weights);
  if (filter_.resample_every_step || last_ess_ < filter_.resample_ess_fraction * NumParticles()) {
    Resample(weights);
  }
}

template <int D>
void FastSlam<D>::ProposeParticle(int p, const std::vector<Segment>& segments, const Eigen::Vector3d& var, double dt,
                                  const std::vector<Detection>& detections, UpdateBatch<D>* batch) {
  Particle& particle = particles_[p];
  // 1. Motion prior.
  PoseProposal proposal = MotionPrior(particle, segments, var);
  // 2. Landmark prediction.
  PredictLandmarks(&particle, dt);
  // 3-4. Association and proposal.
  AssociateDetections(p, detections, &proposal);
  SamplePose(&particle, proposal);
  // 5. Landmark updates at the sampled pose; new landmarks.
  UpdateLandmarks(p, detections, batch);
}

template <int D>
typename FastSlam<D>::PoseProposal FastSlam<D>::MotionPrior(const Particle& particle,
                                                            const std::vector<Segment>& segments,
                                                            const Eigen::Vector3d& var) {
  // N(mu, Sigma). From the IMU the particle's speed is v ~ N(v_p + dv, q) (q = imu_speed_var_),
  // which moves the pose along the direction of travel u by dt (v - v_p - dv): the pose prior
  // gains dt^2 q u u^T.
  PoseProposal prior;
  Pose2& mu = prior.mu;
  Eigen::Matrix3d& sigma = prior.sigma;
  mu = particle.pose;
  if (imu_step_) {
    const Segment& s = segments.front();
    prior.v_prior = particle.speed_mps + imu_speed_change_;
    prior.u = Eigen::Vector2d(std::cos(mu.heading + 0.5 * s.w_radps * s.dt_s),
                              std::sin(mu.heading + 0.5 * s.w_radps * s.dt_s));
    mu = common::UnicycleStep(mu, prior.v_prior, s.w_radps, s.dt_s);
    prior.prior_xy = mu.Translation();
    sigma.topLeftCorner<2, 2>() += s.dt_s * s.dt_s * imu_speed_var_ * prior.u * prior.u.transpose();
  } else {
    // The odometry's (v, w) noise through each segment: Sigma = F Sigma F^T + G Q_u G^T.
    for (const auto& s : segments) {
      const common::LinearizedUnicycleStep j = common::UnicycleStepWithJacobians(mu, s.v_mps, s.w_radps, s.dt_s);
      sigma = j.f * sigma * j.f.transpose() + j.g * odometry_var_.asDiagonal() * j.g.transpose();
      mu = j.next;
    }
  }
  sigma += var.asDiagonal();
  prior.prior_along_var = prior.u.dot(sigma.topLeftCorner<2, 2>() * prior.u);
  if (!fastslam2_) {  // FastSLAM 1.0 samples the pose from the motion prior alone
    mu = Pose2::FromVector(mu.Vector() + rng_.Gaussian<3>(sigma));
    sigma.setZero();
  }
  return prior;
}

template <int D>
void FastSlam<D>::AssociateDetections(int p, const std::vector<Detection>& detections, PoseProposal* proposal) {
  const Particle& particle = particles_[p];
  reachable_.Reset();
  used_.assign(particle.count, 0);
  matches_.clear();
  gated_.clear();
  creations_.clear();
  for (const Detection& det : detections) {
    const auto [slot, kind] = Associate(particle, det, *proposal);
    if (kind == AssociationKind::kNew) {
      // Weight: the density at the new-landmark gate under S0 = H_x Sigma H_x^T + R, with H_x
      // at the point the detection sees.
      const Eigen::Vector2d point = common::PointFromRangeBearing(proposal->mu, {det.range_m, det.bearing_rad});
      const Eigen::Matrix<double, 2, 3> hx = MeasurementJacobianPose(point, proposal->mu);
      const Eigen::Matrix2d s0 = hx * proposal->sigma * hx.transpose() + ReadingCovariance();
      log_weights_[p] += -0.5 * log_new_d2_ - std::log(2.0 * kPi) - 0.5 * std::log(s0.determinant());
      creations_.push_back(det.index);
      continue;
    }
    WeighMatch(p, det, slot, kind, proposal);
  }
}

template <int D>
std::pair<int, AssociationKind> FastSlam<D>::Associate(const Particle& particle, const Detection& det,
                                                       const PoseProposal& proposal) {
  const int count = particle.count;
  if (det.landmark_id >= 0) {
    const int slot = FindIdentity(particle, det.landmark_id);
    return {slot,
            slot < 0 ? AssociationKind::kNew : (used_[slot] ? AssociationKind::kIgnored : AssociationKind::kMatched)};
  }
  if (count == 0) return {-1, AssociationKind::kNew};
  const auto [slot, d2] =
      reachable_.Nearest(particle.blocks, count, proposal.mu, proposal.sigma, det.range_m, det.bearing_rad, used_);
  return {slot, slot >= 0 ? gates_.Classify(d2) : AssociationKind::kNew};
}

template <int D>
void FastSlam<D>::WeighMatch(int p, const Detection& det, int slot, AssociationKind kind, PoseProposal* proposal) {
  // Likelihood of z under the chosen landmark: S = H_m P_pp H_m^T + H_x Sigma H_x^T + R.
  const Pose2& mu = proposal->mu;
  Eigen::Matrix3d& sigma = proposal->sigma;
  const Block& block = *particles_[p].blocks[slot / kLanes];
  const int lane = slot % kLanes;
  const Eigen::Vector2d landmark(block.Mean(0, lane), block.Mean(1, lane));
  const RangeBearingModel<double> m =
      PredictMeasurement<double>(landmark.x(), landmark.y(), mu.x, mu.y, mu.heading, det.range_m, det.bearing_rad);
  Eigen::Matrix2d hm;
  hm << m.a00, m.a01, m.a10, m.a11;
  Eigen::Matrix<double, 2, 3> hx;
  hx.leftCols<2>() = -hm;
  hx.col(2) = Eigen::Vector2d(0.0, -1.0);
  Eigen::Matrix2d p_pp;
  p_pp << block.Cov(0, 0, lane), block.Cov(0, 1, lane), block.Cov(0, 1, lane), block.Cov(1, 1, lane);
  const Eigen::Matrix2d s = hm * p_pp * hm.transpose() + hx * sigma * hx.transpose() + ReadingCovariance();
  const Eigen::Vector2d nu(m.nu_r, m.nu_b);
  if (det.landmark_id >= 0 && filter_.outlier_gate_probability < 1.0) {
    // Outlier gate for identified detections (filter.outlier_gate_probability): beyond the
    // chi-square 2 dof gate d2_max = -2 ln(1 - p) a reading is an outlier (a wrong range):
    // its likelihood is capped at the gate and it updates nothing. It keeps its landmark's
    // label: a smoother fed by the labels decides by its own gate, at its own estimate.
    const double d2_max = -2.0 * std::log(1.0 - filter_.outlier_gate_probability);
    const double d2 = nu.dot(s.ldlt().solve(nu));
    if (d2 > d2_max) {
      log_weights_[p] += -0.5 * d2_max - std::log(2.0 * kPi) - 0.5 * std::log(s.determinant());
      if (kind != AssociationKind::kIgnored) gated_.push_back({slot, det.index});
      return;
    }
  }
  log_weights_[p] += common::LogGaussian2(nu, s);
  if (kind == AssociationKind::kIgnored) return;
  used_[slot] = 1;
  matches_.push_back({slot, det.index});
  if (fastslam2_) {
    // Pose EKF update with the landmark's predicted-measurement covariance as noise.
    const Eigen::Matrix<double, 3, 2> k = sigma * hx.transpose() * s.inverse();
    proposal->mu = Pose2::FromVector(mu.Vector() + k * nu);
    sigma = (Eigen::Matrix3d::Identity() - k * hx) * sigma;
    sigma = 0.5 * (sigma + sigma.transpose()).eval();
  }
}

template <int D>
void FastSlam<D>::SamplePose(Particle* particle, const PoseProposal& proposal) {
  Pose2 mu = proposal.mu;
  if (fastslam2_) {
    const Eigen::LLT<Eigen::Matrix3d> llt(proposal.sigma);
    const Eigen::Vector3d n(rng_.Normal(), rng_.Normal(), rng_.Normal());
    const Eigen::Vector3d delta =
        llt.info() == Eigen::Success ? Eigen::Vector3d(llt.matrixL() * n) : rng_.Gaussian<3>(proposal.sigma);
    mu = Pose2::FromVector(mu.Vector() + delta);
  }
  particle->pose = mu;
  if (imu_step_) {
    // The speed given the sampled pose (the scan depends on the speed only through the pose),
    // from the prior's joint Gaussian of (along-track position, speed): gain k = dt q / Var(along).
    const double dt_q = step_dt_s_ * imu_speed_var_;
    const double k = proposal.prior_along_var > 0.0 ? dt_q / proposal.prior_along_var : 0.0;
    particle->speed_mps = proposal.v_prior + k * proposal.u.dot(mu.Translation() - proposal.prior_xy) +
                          rng_.Normal(0.0, std::sqrt(std::max(0.0, imu_speed_var_ - k * dt_q)));
  }
}

template <int D>
void FastSlam<D>::UpdateLandmarks(int p, const std::vector<Detection>& detections, UpdateBatch<D>* batch) {
  Particle& particle = particles_[p];
  const Pose2& pose = particle.pose;
  std::uint32_t* labels = detection_labels_.data() + static_cast<std::size_t>(p) * detections.size();
  for (const Match& match : matches_) {
    Block* block = MutableBlock(&particle, match.slot / kLanes);
    const int lane = match.slot % kLanes;
    LandmarkMeta& meta = block->meta[lane];
    const Detection& det = detections[match.detection];
    if (meta.position_only) {
      StartFullState(block, lane, pose, det);
    } else {
      batch->Add(block, lane, pose, det.range_m, det.bearing_rad);
    }
    ++meta.sightings;
    meta.misses = 0;
    meta.last_seen_step = step_;
    labels[match.detection] = meta.track_id;
  }
  for (const Match& gated : gated_) {
    labels[gated.detection] = particle.blocks[gated.slot / kLanes]->meta[gated.slot % kLanes].track_id;
  }
  for (const int i : creations_) {
    CreateLandmark(&particle, pose, detections[i]);
    labels[i] = creation_ids_[i];
  }
}

template <int D>
typename FastSlam<D>::Block* FastSlam<D>::MutableBlock(Particle* particle, int b) {
  std::shared_ptr<Block>& block = particle->blocks[b];
  if (block.use_count() > 1) block = std::make_shared<Block>(*block);
  return block.get();
}

template <int D>
void FastSlam<D>::PredictLandmarks(Particle* particle, double dt) {
  if constexpr (D == 2) {
    (void)particle;
    (void)dt;
  } else {
    for (int b = particle->still / kLanes; b < static_cast<int>(particle->blocks.size()); ++b) {
      Block* block = MutableBlock(particle, b);
      const int lanes = std::min(kLanes, particle->count - b * kLanes);
      PredictBlock(block, lanes, dt, q_);
      // Landmarks seen once: no motion (v = 0 in the kernel); the position spreads by the
      // displacement of unknown direction; heading and speed stay undefined (zeroed).
      for (int l = 0; l < lanes; ++l) {
        if (block->meta[l].stationary) {
          // Static (v = w = 0 with no variance: the kernel moved nothing): no process noise.
          for (int i = 0; i < D; ++i) block->Cov(i, i, l) -= q_[i];
          continue;
        }
        if (!block->meta[l].position_only) continue;
        for (int i = 2; i < D; ++i) {
          block->Mean(i, l) = 0.0;
          for (int j = 0; j < D; ++j) block->Cov(i, j, l) = 0.0;
        }
        block->Cov(0, 0, l) += unknown_heading_inflation_;
        block->Cov(1, 1, l) += unknown_heading_inflation_;
      }
    }
  }
}

template <int D>
Eigen::Matrix2d FastSlam<D>::PointCovariance(const Pose2& pose, const Detection& det) const {
  // p = (xr + r cos a, yr + r sin a), a = phi + b;  J = d p / d(r, b).
  const double a = pose.heading + det.bearing_rad;
  Eigen::Matrix2d j;
  j << std::cos(a), -det.range_m * std::sin(a), std::sin(a), det.range_m * std::cos(a);
  return j * Eigen::Vector2d(var_r_, var_b_).asDiagonal() * j.transpose();
}

template <int D>
void FastSlam<D>::CreateLandmark(Particle* particle, const Pose2& pose, const Detection& det) {
  const int slot = particle->count;
  if (slot / kLanes == static_cast<int>(particle->blocks.size())) {
    particle->blocks.push_back(std::make_shared<Block>());
  }
  Block* block = MutableBlock(particle, slot / kLanes);
  const int lane = slot % kLanes;
  ++particle->count;
  StateVector<D> mean = StateVector<D>::Zero();
  StateMatrix<D> cov = StateMatrix<D>::Zero();
  mean.template head<2>() = common::PointFromRangeBearing(pose, {det.range_m, det.bearing_rad});
  cov.template topLeftCorner<2, 2>() = PointCovariance(pose, det);
  block->Set(lane, mean, cov);
  if constexpr (D == 3) {
    block->field[Block::kParamV][lane] = 0.0;
    block->field[Block::kParamW][lane] = 0.0;
  }
  std::uint32_t& id = creation_ids_[det.index];
  if (id == 0) id = next_track_id_++;
  LandmarkMeta& meta = block->meta[lane];
  meta = LandmarkMeta{};
  meta.track_id = id;
  meta.landmark_id = det.landmark_id;
  meta.origin_robot = static_cast<std::int16_t>(robot_index_);
  meta.origin_track = id;
  meta.first_seen_step = step_;
  meta.last_seen_step = step_;
  meta.sightings = 1;
  meta.position_only = D > 2;
}

template <int D>
void FastSlam<D>::StartFullState(Block* block, int lane, const Pose2& pose, const Detection& det) {
  if constexpr (D == 2) {
    // Static landmarks start their full state at the first sighting.
    (void)block;
    (void)lane;
    (void)pose;
    (void)det;
  } else {
    LandmarkMeta& meta = block->meta[lane];
    const int n = std::max<int>(1, static_cast<int>(step_ - meta.first_seen_step));
    const double dt = step_dt_s_;
    // First sighting p1 with its covariance before the per-step inflation (c + q per axis).
    const Eigen::Vector2d p1(block->Mean(0, lane), block->Mean(1, lane));
    Eigen::Matrix2d p1_cov;
    p1_cov << block->Cov(0, 0, lane), block->Cov(0, 1, lane), block->Cov(0, 1, lane), block->Cov(1, 1, lane);
    const Eigen::Matrix2d q_xy = Eigen::Vector2d(q_[0], q_[1]).asDiagonal();
    p1_cov -= n * (unknown_heading_inflation_ * Eigen::Matrix2d::Identity() + q_xy);
    p1_cov.diagonal() = p1_cov.diagonal().cwiseMax(1e-12);
    // Second sighting p2, displacement delta = p2 - p1 and its covariance.
    const Eigen::Vector2d p2 = common::PointFromRangeBearing(pose, {det.range_m, det.bearing_rad});
    const Eigen::Matrix2d p2_cov = PointCovariance(pose, det);
    const Eigen::Vector2d delta = p2 - p1;
    const Eigen::Matrix2d delta_cov = p1_cov + p2_cov + n * q_xy;
    const double length = std::max(delta.norm(), 1e-9);
    const Eigen::Vector2d u = delta / length;
    // heading of the chord: theta = atan2(delta), d theta / d delta = (-dy, dx) / |delta|^2.
    const Eigen::RowVector2d j_theta = Eigen::RowVector2d(-delta.y(), delta.x()) / (length * length);
    double heading = std::atan2(delta.y(), delta.x());

    StateVector<D> mean = StateVector<D>::Zero();
    StateMatrix<D> cov = StateMatrix<D>::Zero();
    mean.template head<2>() = p2;
    cov.template topLeftCorner<2, 2>() = p2_cov;
    double heading_var = j_theta.dot(delta_cov * j_theta.transpose()) + q_[2];
    Eigen::Vector2d cov_p_theta = p2_cov * j_theta.transpose();

    if constexpr (D == 3) {
      // The chord's direction is the heading halfway through the turn of the n steps.
      const std::size_t c = PickCandidate(block, lane, length, u.dot(delta_cov * u), n);
      heading += 0.5 * (n - 1) * filter_.known_kinematics[c].w_radps * dt;
    }
    if constexpr (D == 5) {
      if (SampleStationary(delta, delta_cov, n)) {
        StartStationary(block, lane, p1, p1_cov, p2, p2_cov);
        return;
      }
      // v = |delta| / (n dt); w unknown: prior N(0, sd_w^2); heading = chord + (n - 1) w dt / 2.
      const double t = n * dt;
      const double w_var = filter_.landmark_turn_rate_prior_sd_radps * filter_.landmark_turn_rate_prior_sd_radps;
      const double lever = 0.5 * (n - 1) * dt;
      mean(3) = length / t;
      cov(3, 3) = u.dot(delta_cov * u) / (t * t) + q_[3];
      cov.template block<2, 1>(0, 3) = p2_cov * u / t;
      cov(2, 3) = j_theta.dot(delta_cov * u) / t;
      cov(4, 4) = w_var;
      cov(2, 4) = lever * w_var;
      heading_var += lever * lever * w_var;
    }
    // A heading known no better than uniform is capped there; its cross-covariances are scaled
    // by the same factor's square root, which keeps the matrix positive semidefinite.
    if (heading_var > kUnknownHeadingVar) {
      const double f = std::sqrt(kUnknownHeadingVar / heading_var);
      cov_p_theta *= f;
      for (int i = 3; i < D; ++i) cov(2, i) *= f;
      heading_var = kUnknownHeadingVar;
    }
    mean(2) = WrapAngle(heading);
    cov(2, 2) = heading_var;
    cov.template block<2, 1>(0, 2) = cov_p_theta;
    cov = cov.template selfadjointView<Eigen::Upper>();
    block->Set(lane, mean, cov);
    meta.position_only = false;
  }
}

template <int D>
std::size_t FastSlam<D>::PickCandidate(Block* block, int lane, double length, double var_len, int n) {
  // P(c) ~ exp(-(|delta| - chord_c)^2 / (2 u^T C_delta u)).
  const auto& candidates = filter_.known_kinematics;
  std::vector<double> log_l(candidates.size());
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const double e = length - ChordLength(candidates[c].v_mps, candidates[c].w_radps, step_dt_s_, n);
    log_l[c] = -0.5 * e * e / var_len;
  }
  const std::vector<double> prob = NormalizeLogWeights(&log_l);
  double pick = rng_.Uniform();
  std::size_t c = 0;
  while (c + 1 < prob.size() && pick >= prob[c]) pick -= prob[c++];
  if constexpr (D == 3) {
    block->field[Block::kParamV][lane] = candidates[c].v_mps;
    block->field[Block::kParamW][lane] = candidates[c].w_radps;
  }
  block->meta[lane].candidate = static_cast<std::int8_t>(c);
  return c;
}

template <int D>
void FastSlam<D>::StartStationary(Block* block, int lane, const Eigen::Vector2d& p1, const Eigen::Matrix2d& p1_cov,
                                  const Eigen::Vector2d& p2, const Eigen::Matrix2d& p2_cov) {
  const Eigen::Matrix2d i1 = p1_cov.inverse(), i2 = p2_cov.inverse();
  const Eigen::Matrix2d p = (i1 + i2).inverse();
  StateVector<D> mean = StateVector<D>::Zero();
  StateMatrix<D> cov = StateMatrix<D>::Zero();
  mean.template head<2>() = p * (i1 * p1 + i2 * p2);
  cov.template topLeftCorner<2, 2>() = 0.5 * (p + p.transpose());
  if constexpr (D > 2) cov(2, 2) = kUnknownHeadingVar;
  block->Set(lane, mean, cov);
  block->meta[lane].position_only = false;
  block->meta[lane].stationary = true;
}

template <int D>
bool FastSlam<D>::SampleStationary(const Eigen::Vector2d& delta, const Eigen::Matrix2d& delta_cov, int steps) {
  const double prior = filter_.landmark_static_prior;
  if (prior <= 0.0) return false;
  // Static: delta ~ N(0, C). Moving: delta = s t u with u uniform in direction and s uniform in
  // [0, s_max], of density 1 / (2 pi |delta| s_max t) within s_max t (|delta| floored at the
  // noise's scale, where the noise blurs that density's peak at zero).
  const double log_static = common::LogGaussian2(delta, delta_cov);
  const double reach = MaxLandmarkSpeed(filter_) * step_dt_s_ * steps;
  const double noise = std::sqrt(0.5 * delta_cov.trace());
  const double log_moving = -std::log(2.0 * kPi * std::max(delta.norm(), noise) * reach);
  const double odds = std::log(prior / (1.0 - prior)) + log_static - log_moving;
  const double p_static = 1.0 / (1.0 + std::exp(-odds));
  return rng_.Uniform() < p_static;
}

template <int D>
int FastSlam<D>::FindIdentity(const Particle& particle, int landmark_id) const {
  for (int s = 0; s < particle.count; ++s) {
    if (particle.blocks[s / kLanes]->meta[s % kLanes].landmark_id == landmark_id) return s;
  }
  return -1;
}

template <int D>
bool FastSlam<D>::InView(const Pose2& pose, double x, double y) const {
  const double dx = x - pose.x, dy = y - pose.y;
  const double r2 = dx * dx + dy * dy;
  if (r2 > lidar_.max_range_m * lidar_.max_range_m || r2 < lidar_.min_range_m * lidar_.min_range_m) {
    return false;
  }
  if (lidar_.fov_rad >= 2.0 * kPi) return true;
  // |bearing| <= fov / 2  <=>  cos(bearing) >= cos(fov / 2).
  const double along = dx * std::cos(pose.heading) + dy * std::sin(pose.heading);
  return along >= std::sqrt(r2) * std::cos(0.5 * lidar_.fov_rad);
}

template <int D>
void FastSlam<D>::CountMisses(int p) {
  Particle& particle = particles_[p];
  int s = 0;
  while (s < particle.count) {
    const Block& view = *particle.blocks[s / kLanes];
    const int lane = s % kLanes;
    if (Lost(view.Cov(0, 0, lane), view.Cov(0, 1, lane), view.Cov(1, 1, lane))) {
      RemoveLandmark(&particle, s);  // the last landmark moves into slot s
      continue;
    }
    if (view.meta[lane].last_seen_step == step_ || !InView(particle.pose, view.Mean(0, lane), view.Mean(1, lane))) {
      ++s;
      continue;
    }
    Block* block = MutableBlock(&particle, s / kLanes);
    if (++block->meta[lane].misses >= filter_.drop_after_misses) {
      RemoveLandmark(&particle, s);  // the last landmark moves into slot s
    } else {
      ++s;
    }
  }
}

template <int D>
void FastSlam<D>::GatherStationary(Particle* particle) {
  int front = particle->still, back = particle->count - 1;
  const auto stationary = [&](int s) { return particle->blocks[s / kLanes]->meta[s % kLanes].stationary; };
  while (true) {
    while (front <= back && stationary(front)) ++front;
    while (back > front && !stationary(back)) --back;
    if (front >= back) break;
    SwapSlots(particle, front++, back--);
  }
  particle->still = front;
}

template <int D>
void FastSlam<D>::SwapSlots(Particle* particle, int a, int b) {
  Block held;
  particle->blocks[a / kLanes]->CopyLane(a % kLanes, &held, 0);
  const Block& from = *particle->blocks[b / kLanes];
  from.CopyLane(b % kLanes, MutableBlock(particle, a / kLanes), a % kLanes);
  held.CopyLane(0, MutableBlock(particle, b / kLanes), b % kLanes);
}

template <int D>
void FastSlam<D>::RemoveLandmark(Particle* particle, int slot) {
  particle->still = std::min(particle->still, slot);
  const int last = particle->count - 1;
  if (slot != last) {
    const Block& from = *particle->blocks[last / kLanes];
    from.CopyLane(last % kLanes, MutableBlock(particle, slot / kLanes), slot % kLanes);
  }
  particle->count = last;
  if (last % kLanes == 0) particle->blocks.pop_back();
}

template <int D>
void FastSlam<D>::Resample(const std::vector<double>& weights) {
  const std::vector<int> parents = SystematicResample(weights, &rng_);
  std::vector<Particle> next;
  next.reserve(parents.size());
  // Copies share the landmark blocks (shared_ptr); a block is cloned when first written.
  for (const int parent : parents) next.push_back(particles_[parent]);
  particles_ = std::move(next);
  log_weights_.assign(particles_.size(), -std::log(static_cast<double>(particles_.size())));
}

template <int D>
void FastSlam<D>::EstimatePose(const std::vector<double>& w) {
  // Weighted mean, circular mean heading atan2(sum w sin, sum w cos), covariance with wrapped
  // heading differences (weights normalized).
  double sx = 0.0, sy = 0.0, sc = 0.0, ss = 0.0;
  for (int p = 0; p < NumParticles(); ++p) {
    const Pose2& x = particles_[p].pose;
    sx += w[p] * x.x;
    sy += w[p] * x.y;
    sc += w[p] * std::cos(x.heading);
    ss += w[p] * std::sin(x.heading);
  }
  pose_ = {sx, sy, std::atan2(ss, sc)};
  pose_covariance_.setZero();
  for (int p = 0; p < NumParticles(); ++p) {
    const Pose2& x = particles_[p].pose;
    const Eigen::Vector3d d(x.x - pose_.x, x.y - pose_.y, WrapAngle(x.heading - pose_.heading));
    pose_covariance_ += w[p] * d * d.transpose();
  }
}

template <int D>
FilterEstimate FastSlam<D>::Estimate() const {
  FilterEstimate e;
  e.step = step_;
  e.time_s = time_s_;
  e.particles = NumParticles();
  e.effective_sample_size = last_ess_;
  e.pose = pose_;
  e.covariance = pose_covariance_;
  e.labels_detections = true;
  e.detection_tracks = detection_tracks_;
  if (!map_estimate_.value) map_estimate_.value = MapEstimate();
  e.landmarks = *map_estimate_.value;
  return e;
}

template <int D>
template <typename Fn>
void FastSlam<D>::ForEachBlock(Fn&& fn) const {
  // The block after block b of particle p, or the first block of a later particle.
  const auto ahead = [&](int p, int b) -> const Block* {
    for (; p < NumParticles(); ++p, b = 0) {
      if (b * kLanes < particles_[p].count) return particles_[p].blocks[b].get();
    }
    return nullptr;
  };
  const Block* next = ahead(0, 0);
  for (int p = 0; p < NumParticles(); ++p) {
    const Particle& particle = particles_[p];
    for (int b = 0; b * kLanes < particle.count; ++b) {
      const Block* block = next;
      next = ahead(p, b + 1);
      if (next != nullptr) PrefetchBlock(next);
      fn(p, b * kLanes, *block, std::min(kLanes, particle.count - b * kLanes));
    }
  }
}

template <int D>
std::vector<MapLandmark> FastSlam<D>::MapEstimate() const {
  std::vector<double> w(NumParticles());
  double sw = 0.0;
  for (int p = 0; p < NumParticles(); ++p) {
    w[p] = std::exp(log_weights_[p]);
    sw += w[p];
  }
  // Per track id, the weight of its holders and weighted sums (see the class comment), each
  // summed in the order of the particles and their slots.
  TrackTable table;
  auto for_each_landmark = [&](auto&& fn) {
    ForEachBlock([&](int p, int first_slot, const Block& b, int lanes) {
      for (int l = 0; l < lanes; ++l) fn(w[p], b, l, table.tracks()[table.Find(first_slot + l, b.meta[l].track_id)]);
    });
  };
  auto has_heading = [](const Block& b, int l) { return D > 2 && !b.meta[l].position_only; };
  for_each_landmark([&](double wp, const Block& b, int l, TrackAccumulator& a) {
    a.weight += wp;
    a.xy += wp * Eigen::Vector2d(b.Mean(0, l), b.Mean(1, l));
    if (b.meta[l].sightings < filter_.confirm_sightings) a.tentative_weight += wp;
    if (!b.meta[l].stationary) a.moving_weight += wp;
    a.out.landmark_id = b.meta[l].landmark_id;
    a.out.origin_robot = b.meta[l].origin_robot;
    a.out.origin_track = b.meta[l].origin_track;
    a.out.last_seen_step = std::max(a.out.last_seen_step, b.meta[l].last_seen_step);
    a.first_seen = std::min(a.first_seen, b.meta[l].first_seen_step);
    if (has_heading(b, l)) {
      a.heading_weight += wp;
      a.c += wp * std::cos(HeadingOf(b, l));
      a.s += wp * std::sin(HeadingOf(b, l));
      a.v += wp * SpeedOf(b, l);
      a.v_var += wp * SpeedVarOf(b, l);
      a.w += wp * TurnRateOf(b, l);
    }
  });
  for (TrackAccumulator& a : table.tracks()) {
    a.out.first_seen_step = a.first_seen;
    a.out.mean.template head<2>() = a.xy / a.weight;
    a.out.mean(2) = a.heading_weight > 0.0 ? std::atan2(a.s, a.c) : 0.0;
  }
  for_each_landmark([&](double wp, const Block& b, int l, TrackAccumulator& a) {
    const Eigen::Vector2d d(b.Mean(0, l) - a.out.mean(0), b.Mean(1, l) - a.out.mean(1));
    Eigen::Matrix2d p;
    p << b.Cov(0, 0, l), b.Cov(0, 1, l), b.Cov(0, 1, l), b.Cov(1, 1, l);
    a.second.template topLeftCorner<2, 2>() += wp * (p + d * d.transpose()) / a.weight;
    if (has_heading(b, l)) {
      const double dh = WrapAngle(HeadingOf(b, l) - a.out.mean(2));
      const double wh = wp / a.heading_weight;
      a.second(2, 2) += wh * (HeadingCovOf(b, 2, l) + dh * dh);
      a.second(0, 2) += wh * (HeadingCovOf(b, 0, l) + d.x() * dh);
      a.second(1, 2) += wh * (HeadingCovOf(b, 1, l) + d.y() * dh);
    }
  });
  std::vector<MapLandmark> map;  // by track id
  for (const TrackAccumulator& a : table.tracks()) {
    if (a.weight <= 0.5 * sw) continue;  // held by at most half of the weight
    map.push_back(TrackLandmark(a.id, a, D));
  }
  std::sort(map.begin(), map.end(), [](const MapLandmark& a, const MapLandmark& b) { return a.track_id < b.track_id; });
  return map;
}

template <int D>
int FastSlam<D>::MergeLandmarks(const std::vector<MapLandmark>& in, MapFusionRule rule, double gate_probability,
                                double too_close_m) {
  if (in.empty()) return 0;
  map_estimate_.value.reset();
  const double gate = common::ChiSquare2Quantile(gate_probability);
  std::vector<MatchCandidate> incoming;
  incoming.reserve(in.size());
  for (const auto& l : in) {
    incoming.push_back({l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id,
                        OriginKey(l.origin_robot, l.origin_track), l.motion == LandmarkMotionKind::kStatic});
  }
  std::vector<std::uint32_t> new_ids(in.size(), 0);  // one track id per added landmark
  std::vector<MatchCandidate> own;
  FusedBlocks fused;
  for (Particle& particle : particles_) {
    OwnCandidates(particle, &own);
    const std::vector<int> match = MatchLandmarks(own, incoming, gate, too_close_m);
    FuseMatches(&particle, match, in, rule, &fused);
    for (std::size_t i = 0; i < in.size(); ++i) {
      const MapLandmark& peer = in[i];
      // Unmatched: a new landmark in this particle, from the peer's estimate, unless it is
      // already too uncertain to keep (it would leave the map at once).
      if (match[i] == -1 && !Lost(peer.covariance(0, 0), peer.covariance(0, 1), peer.covariance(1, 1))) {
        AddPeerLandmark(&particle, peer, PeerHeadingKnown<D>(peer), &new_ids[i]);
      }
    }
  }
  int added = 0;
  for (const std::uint32_t id : new_ids) added += id != 0 ? 1 : 0;
  return added;
}

template <int D>
void FastSlam<D>::OwnCandidates(const Particle& particle, std::vector<MatchCandidate>* own) const {
  own->clear();
  for (int s = 0; s < particle.count; ++s) {
    const Block& b = *particle.blocks[s / kLanes];
    const int l = s % kLanes;
    Eigen::Matrix2d c;
    c << b.Cov(0, 0, l), b.Cov(0, 1, l), b.Cov(0, 1, l), b.Cov(1, 1, l);
    own->push_back({{b.Mean(0, l), b.Mean(1, l)},
                    c,
                    b.meta[l].landmark_id,
                    OriginKey(b.meta[l].origin_robot, b.meta[l].origin_track),
                    D == 2 || b.meta[l].stationary});
  }
}

template <int D>
void FastSlam<D>::FuseMatches(Particle* particle, const std::vector<int>& match, const std::vector<MapLandmark>& in,
                              MapFusionRule rule, FusedBlocks* fused) {
  LanePeers none;
  none.fill(-1);
  std::vector<LanePeers> peers(particle->blocks.size(), none);
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (match[i] >= 0) peers[match[i] / kLanes][match[i] % kLanes] = static_cast<int>(i);
  }
  const auto fuse = [&](Block* block, const LanePeers& lanes) {
    for (int l = 0; l < kLanes; ++l) {
      if (lanes[l] >= 0) FusePeerLandmark(block, l, in[lanes[l]], rule);
    }
  };
  for (std::size_t b = 0; b < peers.size(); ++b) {
    if (peers[b] == none) continue;
    std::shared_ptr<Block>& block = particle->blocks[b];
    if (block.use_count() == 1) {  // this particle's alone (a block fused once is held by fused too)
      fuse(block.get(), peers[b]);
      continue;
    }
    const auto [first, last] = fused->equal_range(block.get());
    const auto same = std::find_if(first, last, [&](const auto& entry) { return entry.second.peers == peers[b]; });
    if (same != last) {
      block = same->second.fused;
      continue;
    }
    auto copy = std::make_shared<Block>(*block);
    fuse(copy.get(), peers[b]);
    fused->emplace(block.get(), FusedBlock{block, peers[b], copy});
    block = std::move(copy);
  }
}

template <int D>
void FastSlam<D>::FusePeerLandmark(Block* block, int lane, const MapLandmark& peer, MapFusionRule rule) {
  const bool fuse_heading = PeerHeadingKnown<D>(peer) && !block->meta[lane].position_only;
  StateVector<D> x = block->MeanVector(lane);
  StateMatrix<D> p = block->CovMatrix(lane);
  bool fused = false;
  if constexpr (D > 2) {
    if (fuse_heading) fused = FuseObservation<D, 3>(&x, &p, peer.mean, peer.covariance, rule, 2);
  }
  if (!fuse_heading) {
    fused = FuseObservation<D, 2>(&x, &p, peer.mean.head<2>(), peer.covariance.topLeftCorner<2, 2>(), rule);
  }
  if (fused) block->Set(lane, x, p);
  LandmarkMeta& meta = block->meta[lane];
  if (meta.landmark_id < 0) meta.landmark_id = peer.landmark_id;
}

template <int D>
void FastSlam<D>::AddPeerLandmark(Particle* particle, const MapLandmark& peer, bool peer_heading,
                                  std::uint32_t* track_id) {
  const int slot = particle->count;
  if (slot / kLanes == static_cast<int>(particle->blocks.size())) {
    particle->blocks.push_back(std::make_shared<Block>());
  }
  Block* block = MutableBlock(particle, slot / kLanes);
  const int lane = slot % kLanes;
  ++particle->count;
  // A landmark the peer takes as static stays static here (constant turn rate): v = w = 0
  // with no variance, no heading.
  const bool stationary = D == 5 && peer.motion == LandmarkMotionKind::kStatic;
  SetPeerState(block, lane, peer, peer_heading, stationary);
  if (*track_id == 0) *track_id = next_track_id_++;
  LandmarkMeta& meta = block->meta[lane];
  meta = LandmarkMeta{};
  meta.track_id = *track_id;
  meta.landmark_id = peer.landmark_id;
  meta.origin_robot = static_cast<std::int16_t>(peer.origin_robot);
  meta.origin_track = peer.origin_track;
  meta.first_seen_step = step_;
  meta.last_seen_step = std::min(step_, peer.last_seen_step);
  meta.sightings = static_cast<std::uint16_t>(std::max(1, filter_.confirm_sightings));
  meta.stationary = stationary;
  meta.position_only = D > 2 && !peer_heading && !stationary;
  if constexpr (D == 3) {
    if (peer_heading) {
      meta.candidate =
          static_cast<std::int8_t>(NearestKnownKinematics(filter_.known_kinematics, peer.v_mps, peer.w_radps));
    }
  }
}

template <int D>
void FastSlam<D>::SetPeerState(Block* block, int lane, const MapLandmark& peer, bool peer_heading, bool stationary) {
  StateVector<D> mean = StateVector<D>::Zero();
  StateMatrix<D> cov = StateMatrix<D>::Zero();
  mean.template head<2>() = peer.mean.head<2>();
  cov.template topLeftCorner<2, 2>() = peer.covariance.topLeftCorner<2, 2>();
  if constexpr (D > 2) {
    if (stationary) {
      cov(2, 2) = kUnknownHeadingVar;
    } else if (peer_heading) {
      mean(2) = WrapAngle(peer.mean(2));
      cov.template topLeftCorner<3, 3>() = peer.covariance;
    }
  }
  if constexpr (D == 3) {
    block->field[Block::kParamV][lane] = peer_heading ? peer.v_mps : 0.0;
    block->field[Block::kParamW][lane] = peer_heading ? peer.w_radps : 0.0;
  }
  if constexpr (D == 5) {
    if (peer_heading && !stationary) {
      // The snapshot carries no speed or turn-rate variances: the priors of a new state.
      const double s_max = MaxLandmarkSpeed(filter_);
      mean(3) = peer.v_mps;
      mean(4) = peer.w_radps;
      cov(3, 3) = 0.25 * s_max * s_max + q_[3];
      cov(4, 4) = filter_.landmark_turn_rate_prior_sd_radps * filter_.landmark_turn_rate_prior_sd_radps;
    }
  }
  block->Set(lane, mean, cov);
}

template <int D>
bool FastSlam<D>::Reseat(const Pose2& pose, const Eigen::Matrix3d& covariance) {
  for (auto& particle : particles_) particle.pose = Pose2::FromVector(pose.Vector() + rng_.Gaussian<3>(covariance));
  pose_ = pose;
  pose_covariance_ = covariance;
  return true;
}

template <int D>
bool FastSlam<D>::ObserveKnownRobot(const Eigen::Vector2d& position, const Eigen::Matrix2d& covariance, double range_m,
                                    double bearing_rad, double gate) {
  if (!position.allFinite() || !covariance.allFinite() || !std::isfinite(range_m) || !std::isfinite(bearing_rad)) {
    return false;
  }
  // The innovation of the detection from pose x, its covariance without the pose's uncertainty
  // (S = H C H^T + R) and H_x = d(range, bearing)/d(pose) = [-H | (0, -1)^T].
  struct Innovation {
    Eigen::Vector2d nu;
    Eigen::Matrix2d s;
    Eigen::Matrix<double, 2, 3> hx;
  };
  const auto innovation = [&](const Pose2& x) {
    const double dx = position.x() - x.x, dy = position.y() - x.y;
    const double q = std::max(dx * dx + dy * dy, 1e-12), r = std::sqrt(q);
    Eigen::Matrix2d h;
    h << dx / r, dy / r, -dy / q, dx / q;
    Innovation out{
        {range_m - r, WrapAngle(bearing_rad - (std::atan2(dy, dx) - x.heading))}, h * covariance * h.transpose(), {}};
    out.s(0, 0) += var_r_;
    out.s(1, 1) += var_b_;
    out.hx << -h, Eigen::Vector2d(0.0, -1.0);
    return out;
  };
  // The outlier test: at the mean pose, against S + H_x Sigma H_x^T (Sigma the particles' pose
  // covariance).
  const Innovation at_mean = innovation(pose_);
  const Eigen::Matrix2d s_mean = at_mean.s + at_mean.hx * pose_covariance_ * at_mean.hx.transpose();
  if (!(at_mean.nu.dot(s_mean.ldlt().solve(at_mean.nu)) <= gate)) return false;
  map_estimate_.value.reset();
  for (int p = 0; p < NumParticles(); ++p) {
    const Innovation z = innovation(particles_[p].pose);
    log_weights_[p] += common::LogGaussian2(z.nu, z.s);
  }
  NormalizeLogWeights(&log_weights_);
  return true;
}

template class FastSlam<2>;
template class FastSlam<3>;
template class FastSlam<5>;

std::unique_ptr<SlamFilter> CreateFastSlam(const AgentOptions& options, std::uint64_t seed) {
  switch (options.filter.landmark_kinematics) {
    case LandmarkKinematics::kStatic:
      return std::make_unique<FastSlam<2>>(options, seed);
    case LandmarkKinematics::kKnownCandidates:
      return std::make_unique<FastSlam<3>>(options, seed);
    case LandmarkKinematics::kConstantTurnRate:
      return std::make_unique<FastSlam<5>>(options, seed);
  }
  return nullptr;
}

}  // namespace mrslam::robot_agent::filters
