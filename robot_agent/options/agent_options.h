#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "common/se2.h"
#include "common/sensor_options.h"

// What an agent is told: its own id and start, the team's ids, the sensor and noise models, and
// the filter, rendezvous and cooperation settings. The scenario (common/config/) holds the ground
// truth besides; the agent's code sees only these structs, which the agent's main projects from
// it (AgentOptionsFor).
namespace mrslam::robot_agent {

enum class MotionSource { kOdometry, kImu };
enum class Association { kMahalanobis, kEuclidean };
enum class Proposal { kMotion, kMeasurement };  // FastSLAM 1.0 / 2.0
// What the agent knows of landmark kinematics: all static; a set of candidate (v, w) pairs
// (paper A); or unknown, estimated online with a constant-turn-rate state.
enum class LandmarkKinematics { kStatic, kKnownCandidates, kConstantTurnRate };

struct KnownKinematics {
  double v_mps = 0.0;
  double w_radps = 0.0;
};

// The online smoother (filter.type smoother; docs/smoother.md): a fixed-lag keyframe graph fed by a
// FastSLAM front end that labels the readings.
struct SmootherOptions {
  int window_keyframes = 40;        // keyframes kept as unknowns; older ones are marginalized
  int max_keyframe_gap_steps = 10;  // a keyframe at least this often, readings or not
  int front_end_particles = 50;     // the front end's particles
  int max_iterations = 1;           // Levenberg-Marquardt iterations per solve
  // When a variable of the marginalization prior has moved further than this from where the prior
  // was linearized (metres, radians; the correction's components as they are), the whole run is
  // solved again and the prior rebuilt at that solution (0: never).
  double relinearize_threshold = 0.0;
  // 0: a relinearization is done as soon as it is due. Otherwise it is solved on a thread of its
  // own while the steps go on, and applied at the first keyframe this many steps after it fell
  // due (the same step whatever its duration, so runs stay repeatable); below window_keyframes.
  int relinearize_delay_steps = 0;
  double huber_k = 3.0;                      // the Huber loss's width on a reading's whitened residual norm
  double reading_gate_probability = 0.9999;  // chi-square 2 dof gate of a reading at the solution
  // Prior standard deviations of the odometry correction: speed factor, turn-rate factor,
  // turn-rate bias (rad/s), about (1, 1, 0). The defaults say the configured calibration is
  // known well, as in simulation; a real robot's scenario states how well it knows its own.
  double speed_factor_sd = 0.003;
  double turn_factor_sd = 0.003;
  double turn_bias_sd_radps = 0.0015;
  // Lost: this many keyframes in a row with at least min_recovery_readings readings of which at
  // most half fit the map; then the pose is searched again among the mapped landmarks.
  int lost_after_keyframes = 3;
  int min_recovery_readings = 3;
  double max_relocation_m = 2.0;  // how far from the believed pose the search looks
  // Among movers of unknown kinematics (constant_turn_rate): the correlation time in seconds of a
  // mover's velocity, over which the motion of a mover no reading shows dies out (MoverMemory);
  // 0: predicted by its last (v, w) for as long as the front end holds it.
  double mover_memory_s = 1.0;
};

struct FilterOptions {
  std::string type = "fastslam";  // fastslam | ekf | ekf_ela | smoother
  int particles = 1000;
  MotionSource motion_source = MotionSource::kOdometry;
  Proposal proposal = Proposal::kMeasurement;
  Association association = Association::kMahalanobis;
  double gate_probability = 0.999;           // chi-square 2 dof gate
  double new_landmark_probability = 0.9999;  // beyond this gate a detection starts a landmark
  double euclidean_gate = 0.5;               // paper A's threshold on |[dr, db]|
  LandmarkKinematics landmark_kinematics = LandmarkKinematics::kConstantTurnRate;
  std::vector<KnownKinematics> known_kinematics;
  double max_landmark_speed_mps = 1.0;  // bounds the association of a second sighting
  // constant_turn_rate: per-step random-walk variances of a landmark's speed and turn rate, and
  // the prior standard deviation of the turn rate when a landmark's full state starts.
  double landmark_speed_process_var = 1e-4;      // (m/s)^2 per step
  double landmark_turn_rate_process_var = 1e-4;  // (rad/s)^2 per step
  double landmark_turn_rate_prior_sd_radps = 0.5;
  // constant_turn_rate, fastslam: prior probability that a newly seen landmark stands still. At
  // its second sighting each particle takes it as static (fixed, no process noise) or moving
  // (constant turn rate) by this prior and the likelihood of the displacement between the two
  // sightings; the weights settle which is right (0: every landmark has the motion model).
  double landmark_static_prior = 0.5;
  int confirm_sightings = 2;  // tentative until seen this many times
  int drop_after_misses = 5;  // dropped when expected in view but missed this many times
  // FastSLAM: a landmark whose position standard deviation sqrt(var_x + var_y) grows beyond this
  // leaves the map, in view or not (an unseen moving landmark predicted by a model it has left);
  // a peer's landmark beyond it is not merged.
  double max_landmark_position_sd_m = 2.0;
  // ekf_ela (paper B): chi-square 2 dof gate of the expected-landmark-area test; frames a moving
  // landmark must stay within its own gate before it re-enters the map.
  double ela_gate_probability = 0.999;
  int ela_return_after_frames = 5;
  // ekf_ela: frames over which a mapped landmark's position innovations are averaged for the
  // drift test (0: off, as paper B).
  int ela_drift_window_frames = 3;
  // ekf_ela: sightings in a row a mapped landmark must be found outside its area (by the ELA or
  // the drift test) before it is taken out of the map as moving (1: at once, as paper B's rule).
  int ela_outside_frames_to_move = 2;
  // ekf_ela: frames a mapped landmark may be expected in view and not seen before it is deleted
  // (paper B's Algorithm 1: 1).
  int ela_drop_unseen_after_frames = 1;
  // ekf_ela: once the share of observations flagged so far as creeping (by the drift test or the
  // velocity test on return from probation) reaches ela_young_creep_share, a newly mapped landmark
  // corrects only itself, not the pose nor the other landmarks, for its first ela_young_sightings
  // sightings (0: off, as paper B).
  int ela_young_sightings = 10;
  double ela_young_creep_share = 0.005;
  double resample_ess_fraction = 0.5;
  bool resample_every_step = false;
  // Odometry calibration (FastSLAM): the robot moves at odometry_scale times the commanded
  // forward speed and odometry_turn_scale times the commanded turn rate, odometry_lag_s after
  // the command (MRCLAM robots: about 0.92, 0.91 and 0.2 s).
  double odometry_scale = 1.0;
  double odometry_turn_scale = 1.0;
  double odometry_lag_s = 0.0;
  // FastSLAM, identified detections: beyond this chi-square 2 dof gate a reading is an outlier
  // and ignored (1: no gate).
  double outlier_gate_probability = 1.0;
  SmootherOptions smoother;
};

struct RendezvousOptions {
  int enable_from_step = 0;     // the detector may fire only from this step
  int window_steps = 1;         // both detections must fall within this many steps
  int min_interval_steps = 20;  // between repeated rendezvous of one pair
};

// How an agent fuses a peer's landmark with its own matched landmark (docs/cooperation.md).
enum class MapFusionRule { kCovarianceIntersection, kWeighted, kAverage };

// Cooperation among robots: frame transforms from mutual detections, map snapshots and their
// merging, cooperative localization.
struct CooperationOptions {
  MapFusionRule map_fusion = MapFusionRule::kCovarianceIntersection;
  bool merge_maps = true;            // send snapshots at a rendezvous and merge received ones
  int max_snapshot_landmarks = 256;  // size bound of a snapshot; larger ones are rejected
  // A landmark of the own map is shared once it has been seen over at least this many steps
  // (first to last sighting): a slow mover that the filter briefly took as static, and then lost,
  // stays out of the peers' maps, where no robot would see it gone.
  int min_seen_span_steps = 6;
  bool cooperative_localization = false;  // mutual detections also correct the own pose
  double match_gate_probability = 0.999;  // chi-square 2 dof gate, peer vs own landmark
  // A static peer landmark that matches no own one within the gate but lies closer than this to
  // a static own one is most likely the same landmark placed off by the peer's map or the
  // transform: it is left out rather than added as a second copy (0: off).
  double merge_min_separation_m = 1.5;
  // A mutual detection whose transform disagrees with the one held beyond this chi-square 3 dof
  // gate is not fused (an outlier: e.g. a detection paired with the wrong robot).
  double transform_gate_probability = 0.9999;
  // At a rendezvous the snapshot also carries the sender's history (odometry and labelled scans
  // since its first step, at most max_history_steps of them), and the receiver estimates the
  // transform from both robots' histories at once (a joint MAP estimate) instead of aligning
  // the two maps.
  bool joint_transform = true;
  int max_history_steps = 300;
  // Raw measurements shared peer to peer (docs/cooperation.md, "Sharing raw measurements"): every
  // step's odometry and labelled scan, of the own robot and, relayed, of those it heard from, sent
  // to a peer only within exchange_window_steps steps of the own lidar detecting it, at most
  // max_batch_steps steps per message.
  bool share_factors = false;
  int exchange_window_steps = 20;
  int max_batch_steps = 500;
  bool relay_factors = true;  // also pass on other robots' steps (off under DDS-Security)
  // With share_factors: each step shared carries the origin's estimates of the landmarks it read,
  // and every agent shows its peers' landmarks so streamed where its own map has none
  // (cooperation/streamed_landmarks.h).
  bool stream_landmarks = true;
  // With share_factors among static landmarks: the joint graph over everything held solved
  // again every joint_every_s of run time (0: only at the end), and the own estimate corrected
  // by it (cooperation/joint_tracker.h).
  double joint_every_s = 30.0;
};

struct AgentOptions {
  std::string robot_id;
  std::vector<std::string> team;  // every robot's id in the scenario's order, the own included
  common::Pose2 initial_pose;     // the own start pose in the own frame G_i
  double dt_s = 0.1;              // one step
  common::SensorOptions sensors;
  common::NoiseOptions noise;
  FilterOptions filter;
  RendezvousOptions rendezvous;
  CooperationOptions cooperation;

  // Index of a robot in the team, or -1 for a robot that is not in it.
  int TeamIndex(const std::string& id) const {
    for (std::size_t i = 0; i < team.size(); ++i) {
      if (team[i] == id) return static_cast<int>(i);
    }
    return -1;
  }
};

}  // namespace mrslam::robot_agent
