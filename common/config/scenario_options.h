#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "common/se2.h"

// The scenario file: one YAML document that describes the world, the robots, their sensors,
// the agents' filter options and the run mode. Parsed into plain structs by
// CreateScenarioOptions (unknown keys and wrong types throw ScenarioError naming the key) and
// checked by IsValid (ranges and cross-field rules, naming the key, the value and the rule).
namespace mrslam::common {

// Thrown for unreadable files, bad YAML, unknown keys, wrong types and invalid values.
class ScenarioError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class RunMode { kLockstep, kRealtime };

struct RunOptions {
  RunMode mode = RunMode::kLockstep;
  double realtime_factor = 1.0;  // simulated seconds per wall second
  int steps = 100;
  double dt_s = 0.1;
  double ack_timeout_s = 30.0;  // lockstep: an agent silent this long aborts the run
  int domain = 0;               // DDS domain id
};

enum class LandmarkMotionModel { kStatic, kUnicycle, kCardinal, kConstantVelocity };

struct LandmarkMotionOptions {
  LandmarkMotionModel model = LandmarkMotionModel::kStatic;
  double v_mps = 0.0;                                      // unicycle
  double w_radps = 0.0;                                    // unicycle
  double speed_mps = 0.0;                                  // cardinal
  int reverse_every_steps = 20;                            // cardinal
  Eigen::Vector2d velocity_mps = Eigen::Vector2d::Zero();  // constant_velocity
};

struct LandmarkOptions {
  int id = 0;
  Pose2 pose;  // initial pose in the world frame
  LandmarkMotionOptions motion;
};

// A generated field of landmarks (paper B's world): a jittered grid over a rectangle, a share
// of which move in a random cardinal direction, reversing every N steps.
struct LandmarkFieldOptions {
  bool enabled = false;
  int count = 0;
  Eigen::Vector4d area_m = Eigen::Vector4d(-10, -10, 10, 10);  // x_min, y_min, x_max, y_max
  double jitter_m = 0.5;
  double moving_fraction = 0.0;
  double speed_mps = 0.0;
  int reverse_every_steps = 20;
  int first_id = 1;
};

enum class ControlType { kConstant, kSchedule, kArc };

struct ControlSegment {
  double v_mps = 0.0;
  double w_radps = 0.0;
  double duration_s = 0.0;
};

struct ControlOptions {
  ControlType type = ControlType::kConstant;
  double v_mps = 0.0;                    // constant
  double w_radps = 0.0;                  // constant
  std::vector<ControlSegment> segments;  // schedule (then stands still)
  double radius_m = 1.0;                 // arc
  double speed_mps = 0.0;                // arc
  double sweep_rad = 0.0;                // arc (then stands still); 0 = forever
  bool turn_left = true;                 // arc
};

struct RobotOptions {
  std::string id;
  Pose2 initial_pose;    // in the world frame
  Pose2 frame_in_world;  // pose of the robot's own frame G_i in W
  ControlOptions control;
};

struct LidarOptions {
  double max_range_m = 6.0;
  double min_range_m = 0.0;
  double fov_rad = 2.0 * kPi;
  double range_noise_sd_m = 0.03;
  double bearing_noise_sd_rad = 0.03;
  bool report_identity = false;
  double robot_detection_range_m = 6.0;
  double detection_probability = 1.0;
};

struct ImuOptions {
  bool enabled = true;
  int readings_per_step = 1;
  double gyro_noise_sd_radps = 0.01;
  double accel_noise_sd_mps2 = 0.05;
};

struct OdometryOptions {
  double v_noise_sd_mps = 0.0;
  double w_noise_sd_radps = 0.0;
};

struct SensorOptions {
  LidarOptions lidar;
  ImuOptions imu;
  OdometryOptions odometry;
};

// Per-step process noise variances over (x, y, heading), applied to the true motion by the
// simulator and assumed by the filters.
struct NoiseOptions {
  Eigen::Vector3d robot_process_var = Eigen::Vector3d::Constant(0.001);
  Eigen::Vector3d landmark_process_var = Eigen::Vector3d::Constant(0.001);
};

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

struct FilterOptions {
  std::string type = "fastslam";  // fastslam | ekf | ekf_ela
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
};

// Replay of a recorded data set (UTIAS MRCLAM) instead of the simulation. The robots of the
// scenario name the replayed robots (MRCLAM subject n is robot r<n>); run.steps and run.dt_s
// follow from the window: dt_s = step_s, steps = round(duration_s / step_s) (a given run.steps
// may be smaller: the first steps of the window).
struct ReplayOptions {
  bool enabled = false;
  std::string dir;                  // data folder; LoadScenario resolves a relative one (docs/scenario-schema.md)
  double step_s = 0.1;              // one replay step
  double start_s = 0.0;             // window start, seconds after the data set's first time stamp
  double duration_s = 0.0;          // window length (required)
  std::vector<std::string> robots;  // subset of the scenario's robots to replay (empty: all)
};

struct ScenarioOptions {
  std::string name;
  std::uint64_t seed = 1;
  RunOptions run;
  std::vector<LandmarkOptions> landmarks;
  LandmarkFieldOptions landmark_field;
  std::vector<RobotOptions> robots;
  SensorOptions sensors;
  NoiseOptions noise;
  FilterOptions filter;
  RendezvousOptions rendezvous;
  CooperationOptions cooperation;
  ReplayOptions replay;

  // Range and cross-field checks; on failure *error names the key, the value and the rule.
  bool IsValid(std::string* error) const;
  // Index of a robot by id, or -1.
  int RobotIndex(const std::string& id) const;
};

// Parses a scenario document. Throws ScenarioError on unknown keys, missing required keys and
// values of the wrong type.
ScenarioOptions CreateScenarioOptions(const YAML::Node& root);

// Applies one "key.path=value" override (sequence elements by index: robots.1.id=r7) to a
// document. Throws ScenarioError when the path does not lead anywhere.
void ApplyOverride(YAML::Node& root, const std::string& assignment);

// Loads a file, applies overrides in order, parses and validates. Throws ScenarioError with a
// one-line reason.
ScenarioOptions LoadScenario(const std::string& path, const std::vector<std::string>& overrides);

}  // namespace mrslam::common
