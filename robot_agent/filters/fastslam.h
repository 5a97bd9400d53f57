#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/rng.h"
#include "common/sensor_types.h"
#include "robot_agent/filters/association.h"
#include "robot_agent/filters/landmark_ekf.h"
#include "robot_agent/filters/map_fusion.h"
#include "robot_agent/filters/odometry_calibration.h"
#include "robot_agent/filters/reachable_landmarks.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

namespace mrslam::robot_agent::filters {

// FastSLAM (a Rao-Blackwellized particle filter) among moving landmarks, after paper A's
// Algorithm 1 with the fixes of docs/models.md. Each particle owns a robot pose in the agent's frame
// and a map of landmark EKFs of state dimension D (2: static, 3: unicycle with known (v, w),
// 5: constant turn rate), stored in copy-on-write blocks of kLanes landmarks.
//
// One step (Process):
//  1. Motion prior per particle: mu = UnicycleStep(pose, v, w, dt) from odometry (or the IMU),
//     Sigma = G Q_u G^T + Q, Q = diag(noise.robot_process_var), Q_u = diag(sd_v^2, sd_w^2) the
//     odometry's noise (sensors.odometry) through the step's Jacobian G = d mu / d(v, w) (F Sigma
//     F^T + G Q_u G^T over several segments). From the IMU (w = gyro), each particle carries
//     its own speed v_p, integrated from accel_x with its noise: the prior uses
//     v ~ N(v_p + accel_x dt, q), which adds dt^2 q u u^T to Sigma along the direction of travel
//     u; once the pose is sampled (step 4), v_p is sampled from its Gaussian given the pose.
//  2. Every landmark EKF is predicted with its kinematic model (paper A's modification 1:
//     every step after first sight, seen or not). A landmark seen once has no heading yet: its
//     position covariance grows by (s_max dt)^2 / 2 per axis per step (displacement of unknown
//     direction at the largest speed s_max).
//  3. Each detection (in range-bearing order: the scan's order carries no identity) is
//     associated with the particle's landmarks on the predicted measurements: nearest unused
//     landmark by squared Mahalanobis distance under S = H_m P H_m^T + H_x Sigma H_x^T + R;
//     matched within the chi-square gate, new beyond the new-landmark gate, else ignored.
//     Only the landmarks a reading can gate are gated (ReachableLandmarks: a range bound of the
//     distance, exact for the outcome). Reported identities (landmark_id >= 0) are used directly.
//  4. Proposal. FastSLAM 2.0 (default): each match updates the pose Gaussian like an EKF,
//        K = Sigma H_x^T S^-1, mu += K nu, Sigma = (I - K H_x) Sigma,
//     and the pose is sampled from N(mu, Sigma) after the last match. FastSLAM 1.0 samples the
//     pose from the motion prior (Sigma = 0 in the gate).
//     Weight: log w += log N(nu; 0, S) per match or ignored detection (S at the proposal before
//     that match), and log N at the new-landmark gate (d2 = chi2(new_landmark_probability),
//     S = H_x Sigma H_x^T + R) per new landmark.
//  5. The matched landmark EKFs are updated at the sampled pose, all particles in one batch.
//     A landmark's second sighting starts its full state: heading = direction of the
//     displacement between the two sightings (for known candidates, the candidate model is
//     sampled per particle by the likelihood of the displacement length; for constant turn
//     rate, v = length / elapsed time), with covariances from the first-order propagation of
//     both sightings. With constant turn rate each particle first samples whether the landmark
//     stands still (SampleStationary: filter.landmark_static_prior and the displacement's
//     likelihood); a static one is the two sightings fused, v = w = 0 exactly, and no process
//     noise: prediction skips it (each particle keeps its static landmarks in its front slots,
//     whose blocks then stay shared between the copies resampling makes). New landmarks start
//     from the inverse sensor model.
//  6. Landmarks expected in the field of view but not seen drop_after_misses times in a row
//     are removed; a landmark is tentative until seen confirm_sightings times. A landmark whose
//     predicted position standard deviation sqrt(P_xx + P_yy) exceeds max_landmark_position_sd_m
//     is removed too, in view or not: its estimate no longer says where it is (a moving one
//     unseen for long, predicted by a model it has left). The same bound applies to merged
//     landmarks (MergeLandmarks does not add a peer landmark beyond it).
//  7. Weights are normalized in the log domain; low-variance resampling when
//     ESS < resample_ess_fraction * N (or every step).
//
// The reported map (Estimate): landmarks are identified by a track id allocated per detection
// that created a landmark in some particle during that step, so every particle that created a
// landmark from that detection holds it under the same id. A track is reported when the
// particles holding it carry more than half of the total weight; its estimate is the weighted
// mean over those particles (circular mean for heading) and the mixture covariance
// sum w_p (P_p + d_p d_p^T) / sum w_p, d_p = mean_p - mean (heading difference wrapped), all
// predicted to the current step (every landmark is predicted every step); its motion is static
// (constant turn rate) when the holders taking it as static carry more than half of their
// weight. Each detection's track (FilterEstimate::detection_tracks) is the association of the
// particle of largest weight before resampling. The sums run particle after particle, slot after
// slot, in that order only. Every reading changes every particle's weight, so the map is not
// updated in place across steps (that would reorder the sums): it is computed once after each
// change of the particles or weights and kept until the next (map_estimate_); each landmark finds
// its track's sums through the track the previous particle holds at the same slot, by id only
// when that differs.
//
// Owns its particles, its random stream (derived from (seed, robot id)), scratch buffers and one
// cache (map_estimate_, derived from the particles and weights).
// Not thread-safe; pure (no DDS, no wall clock).
template <int D>
class FastSlam : public SlamFilter {
 public:
  FastSlam(const AgentOptions& options, std::uint64_t seed);

  void Process(const common::SensorStep& step) override;
  FilterEstimate Estimate() const override;
  // The particles (poses, speeds, maps: each landmark block once, shared as it was), weights,
  // random stream, calibration, track counter and the last step's estimate and labels.
  void Io(common::Archive& ar) override;
  // The particles (pose, speed, block pointers), each distinct landmark block once, the weights
  // and the step's labels: about N (sizeof(Particle) + 8 + 16 B) + U sizeof(Block) for N
  // particles of B blocks each and U distinct blocks (U <= N B; a map of L landmarks takes
  // ceil(L / kLanes) blocks per particle): flat once the map stops growing.
  std::size_t EstimatorBytes() const override;
  // Map merging (SlamFilter): per particle, incoming landmarks are matched to the particle's
  // (MatchLandmarks: identities or provenance, else Mahalanobis on position); a match is fused by rule
  // (FuseObservation on position, plus heading when both have one); the others are added to
  // every particle under one new track id each, confirmed (the peer confirmed them), except those
  // whose position standard deviation exceeds max_landmark_position_sd_m (step 6) and, per
  // particle, the static ones too close to a static own landmark (kTooClose). Blocks
  // are copied before they are written, so copy-on-write sharing stays intact, and a block that
  // several particles share and that meets the same matches in each is fused once for all.
  int MergeLandmarks(const std::vector<MapLandmark>& landmarks_in_own_frame, MapFusionRule rule,
                     double gate_probability, double too_close_m) override;
  // Cooperative localization: log w_p += log N(nu_p; 0, S_p), nu_p = z - h(pose_p, position),
  // S_p = H C H^T + R, with H = d(range, bearing)/d(position) and R the lidar noise; not applied
  // when the innovation at the mean pose exceeds the gate under S + H_x Sigma H_x^T (Sigma the
  // particles' pose covariance).
  bool ObserveKnownRobot(const Eigen::Vector2d& position, const Eigen::Matrix2d& covariance, double range_m,
                         double bearing_rad, double gate) override;
  // Every particle's pose drawn from N(pose, covariance), weights and maps kept.
  bool Reseat(const common::Pose2& pose, const Eigen::Matrix3d& covariance) override;

  // Introspection for tests and benchmarks.
  int NumParticles() const { return static_cast<int>(particles_.size()); }
  double ParticleWeight(int i) const;
  int ParticleLandmarkCount(int i) const { return particles_[i].count; }
  // Addresses of a particle's landmark blocks (shared between copies until written).
  std::vector<const void*> LandmarkStorage(int i) const;

 private:
  using Block = LandmarkBlock<D>;
  struct Particle {
    common::Pose2 pose;
    double speed_mps = 0.0;  // IMU motion source: this particle's forward speed
    int count = 0;           // landmarks, in slots 0..count-1
    // Constant turn rate: slots 0..still-1 hold landmarks taken as static, gathered there after
    // each step's miss counting. Prediction leaves them alone, so their blocks stay shared
    // between particles; static landmarks added since (from a peer) may lie further on.
    int still = 0;
    std::vector<std::shared_ptr<Block>> blocks;
  };
  struct Detection {
    double range_m = 0.0;
    double bearing_rad = 0.0;
    int landmark_id = -1;
    int index = 0;       // position in the sorted scan
    int scan_index = 0;  // position in the scan as received
  };
  // A piece of the step's motion (from the IMU, v_mps is unused: each particle has its speed).
  using Segment = OdometryCalibration::Motion;
  struct Match {
    int slot;
    int detection;
  };

  // Odometry or IMU -> motion segments for this step and their process noise variances.
  void MotionFromStep(const common::SensorStep& step, std::vector<Segment>* segments, Eigen::Vector3d* variance);
  // A particle's pose proposal N(mu, sigma): the motion prior, refined by each matched detection
  // (FastSLAM 2.0). From the IMU also the prior speed v_prior, the direction of travel u, the
  // prior position and the prior's variance along u.
  struct PoseProposal {
    common::Pose2 mu;
    Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
    double v_prior = 0.0;
    Eigen::Vector2d u = Eigen::Vector2d::Zero();
    Eigen::Vector2d prior_xy = Eigen::Vector2d::Zero();
    double prior_along_var = 0.0;
  };

  // Steps 1-5 for one particle; queues its landmark updates in batch.
  void ProposeParticle(int p, const std::vector<Segment>& segments, const Eigen::Vector3d& var, double dt,
                       const std::vector<Detection>& detections, UpdateBatch<D>* batch);
  // Step 1: the motion prior (FastSLAM 1.0: the pose sampled from it at once).
  PoseProposal MotionPrior(const Particle& particle, const std::vector<Segment>& segments, const Eigen::Vector3d& var);
  // Steps 3-4: associates each detection, weighs particle p by the readings' likelihood and
  // refines the proposal; fills matches_, gated_ and creations_.
  void AssociateDetections(int p, const std::vector<Detection>& detections, PoseProposal* proposal);
  // A detection's landmark slot in the particle (-1 for none) and what to do with it.
  std::pair<int, AssociationKind> Associate(const Particle& particle, const Detection& det,
                                            const PoseProposal& proposal);
  // Weighs particle p by a detection's likelihood under its landmark at slot, and (matched,
  // FastSLAM 2.0) refines the proposal with it.
  void WeighMatch(int p, const Detection& det, int slot, AssociationKind kind, PoseProposal* proposal);
  // Samples the particle's pose from the proposal (IMU: then its speed given the pose).
  void SamplePose(Particle* particle, const PoseProposal& proposal);
  // Step 5: the matched landmarks' updates at the sampled pose (queued in batch), new landmarks.
  void UpdateLandmarks(int p, const std::vector<Detection>& detections, UpdateBatch<D>* batch);
  // A block that a merge fused for one particle, kept for the others that hold the same block
  // with the same matches (after resampling the particles share most blocks): it is fused once
  // and shared, as resampling left it, rather than copied and fused per particle.
  using LanePeers = std::array<int, kLanes>;  // the incoming landmark fused into each lane, -1: none
  struct FusedBlock {
    std::shared_ptr<Block> original;  // held for the merge, so that no new block takes its address
    LanePeers peers;
    std::shared_ptr<Block> fused;
  };
  using FusedBlocks = std::unordered_multimap<const Block*, FusedBlock>;
  // MergeLandmarks' steps for one particle: its landmarks as match candidates; the incoming
  // landmarks fused into the own ones they matched (match[i]: incoming i's slot), each block
  // through fused; a peer landmark fused into a block's lane; a new landmark from a peer's (with
  // a new track id, one per peer landmark across the particles: *track_id, 0 until set), and its
  // state.
  void OwnCandidates(const Particle& particle, std::vector<MatchCandidate>* own) const;
  static void FuseMatches(Particle* particle, const std::vector<int>& match, const std::vector<MapLandmark>& in,
                          MapFusionRule rule, FusedBlocks* fused);
  static void FusePeerLandmark(Block* block, int lane, const MapLandmark& peer, MapFusionRule rule);
  void AddPeerLandmark(Particle* particle, const MapLandmark& peer, bool peer_heading, std::uint32_t* track_id);
  void SetPeerState(Block* block, int lane, const MapLandmark& peer, bool peer_heading, bool stationary);
  // The reading noise R = diag(var_r, var_b).
  Eigen::Matrix2d ReadingCovariance() const { return Eigen::Vector2d(var_r_, var_b_).asDiagonal(); }
  // Step 6 for one particle.
  void CountMisses(int p);
  void Resample(const std::vector<double>& weights);
  void IoParticles(common::Archive& ar);
  void EstimatePose(const std::vector<double>& weights);
  // The map of the estimate: every track held by more than half of the weight, computed from
  // the particles and weights (Estimate keeps it in map_estimate_ until they change).
  std::vector<MapLandmark> MapEstimate() const;
  // Calls fn(p, first_slot, block, lanes) for every block of every particle in order (lanes: the
  // block's slots in use), each block's rows requested from memory one block ahead.
  template <typename Fn>
  void ForEachBlock(Fn&& fn) const;

  Block* MutableBlock(Particle* particle, int b);
  void PredictLandmarks(Particle* particle, double dt);
  // Constant turn rate: moves the landmarks taken as static to the front slots (Particle::still).
  void GatherStationary(Particle* particle);
  void SwapSlots(Particle* particle, int a, int b);
  void CreateLandmark(Particle* particle, const common::Pose2& pose, const Detection& det);
  void StartFullState(Block* block, int lane, const common::Pose2& pose, const Detection& det);
  // Known candidates: samples a landmark's model by the likelihood of its displacement's length
  // (variance var_len) over n steps, sets its speed and turn rate, and returns the candidate.
  std::size_t PickCandidate(Block* block, int lane, double length, double var_len, int n);
  // Constant turn rate, a landmark taken as static: both sightings (p1, p2) see one point, fused;
  // no heading, speed or turn rate.
  void StartStationary(Block* block, int lane, const Eigen::Vector2d& p1, const Eigen::Matrix2d& p1_cov,
                       const Eigen::Vector2d& p2, const Eigen::Matrix2d& p2_cov);
  // Constant turn rate: whether this particle takes a landmark displaced by delta (covariance
  // delta_cov) over `steps` steps since its first sighting as static (filter.landmark_static_prior).
  bool SampleStationary(const Eigen::Vector2d& delta, const Eigen::Matrix2d& delta_cov, int steps);
  void RemoveLandmark(Particle* particle, int slot);
  int FindIdentity(const Particle& particle, int landmark_id) const;
  bool InView(const common::Pose2& pose, double x, double y) const;
  // Whether a landmark of position covariance trace P_xx + P_yy is beyond the bound of step 6.
  // A landmark leaves the map when its position covariance says it is lost (sd beyond the bound)
  // or is no longer positive definite (numerically broken: its likelihood would be undefined).
  bool Lost(double var_x, double cov_xy, double var_y) const {
    const bool positive_definite = var_x > 0.0 && var_y > 0.0 && var_x * var_y - cov_xy * cov_xy > 0.0;
    return !positive_definite || var_x + var_y > max_position_var_;
  }
  // Position covariance of the point seen at (r, b) from pose: J R J^T.
  Eigen::Matrix2d PointCovariance(const common::Pose2& pose, const Detection& det) const;

  const FilterOptions filter_;
  const common::LidarOptions lidar_;
  const common::ImuOptions imu_;
  const common::NoiseOptions noise_;
  const Eigen::Vector2d odometry_var_;  // variances of the odometry's v and w
  const double step_dt_s_;
  const AssociationGates gates_;
  const bool fastslam2_;
  const int robot_index_;  // in the team: the provenance of the landmarks it maps
  double var_r_, var_b_;
  double q_[D] = {};                        // landmark process noise per step
  double unknown_heading_inflation_ = 0.0;  // (s_max dt)^2 / 2, for landmarks seen once
  double log_new_d2_;                       // chi2(new_landmark_probability), for the new-landmark weight
  double max_position_var_;                 // max_landmark_position_sd_m^2
  UpdateBatch<D> batch_;                    // the landmark updates of a step, across particles

  common::Rng rng_;
  std::vector<Particle> particles_;
  std::vector<double> log_weights_;
  double last_ess_;
  common::Pose2 pose_;  // estimate of the last step, from the weights before resampling
  Eigen::Matrix3d pose_covariance_;
  std::uint32_t step_ = 0;
  double time_s_ = 0.0;
  bool imu_step_ = false;            // this step's motion comes from the IMU
  double imu_speed_change_ = 0.0;    // IMU: the step's change of speed, mean(accel_x) dt
  double imu_speed_var_ = 0.0;       // and its variance, sd_a^2 dt^2 / n
  OdometryCalibration calibration_;  // of the wheel odometry (scale, lag)
  std::uint32_t next_track_id_ = 1;
  std::vector<std::uint32_t> creation_ids_;  // per detection of this step, 0 until used
  // Per particle and sorted detection of this step: the track it was matched to or created (0: none).
  std::vector<std::uint32_t> detection_labels_;
  std::vector<std::uint32_t> detection_tracks_;  // the most probable particle's, in scan order

  // A cache, derived from particles_ and log_weights_ alone: the map of the last Estimate, empty
  // until Estimate fills it. Whatever changes particles_ or log_weights_ (Process,
  // MergeLandmarks, ObserveKnownRobot, and any future restore of the filter's state) empties it;
  // a copy of the filter starts without it (rebuilt on demand).
  struct MapCache {
    MapCache() = default;
    MapCache(const MapCache& /*other*/) {}
    MapCache& operator=(const MapCache& /*other*/) {
      value.reset();
      return *this;
    }
    std::optional<std::vector<MapLandmark>> value;
  };
  mutable MapCache map_estimate_;

  // Scratch.
  ReachableLandmarks<D> reachable_;  // the particle's landmarks the step's readings can gate
  std::vector<std::uint8_t> used_;
  std::vector<Match> matches_;
  std::vector<Match> gated_;  // identified detections beyond the outlier gate: labelled, unused
  std::vector<int> creations_;
};

// The FastSLAM filter for the scenario's landmark kinematics (static: D = 2, known candidates:
// D = 3, constant turn rate: D = 5).
std::unique_ptr<SlamFilter> CreateFastSlam(const AgentOptions& options, std::uint64_t seed);

}  // namespace mrslam::robot_agent::filters
