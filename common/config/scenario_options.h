#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "common/se2.h"
#include "common/sensor_options.h"
#include "robot_agent/options/agent_options.h"

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
  // Realtime: robot i of n gets its sensor data of a step i / n of a period after the step's
  // clock (robots whose sensors are not synchronized); false: all at the step's start.
  bool stagger_robots = true;
  int steps = 100;
  double dt_s = 0.1;
  double ack_timeout_s = 30.0;  // lockstep: an agent silent this long aborts the run
  int horizon_steps = 1000;     // an agent rejects samples and peer messages further ahead
  // A restarted agent restores its snapshot, written every snapshot_every_steps steps, and takes
  // the steps since from DDS, which keeps history_steps steps of every stream.
  int snapshot_every_steps = 50;
  int history_steps = 200;
  int domain = 0;  // DDS domain id
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

// A slip: at the end of step `step` the robot's true pose moves by `displacement` (in its body
// frame: forward, left, heading) while its odometry does not show it (wheels that slide, a robot
// pushed or carried).
struct SlipOptions {
  int step = 1;
  Pose2 displacement;
};

struct RobotOptions {
  std::string id;
  Pose2 initial_pose;    // in the world frame
  Pose2 frame_in_world;  // pose of the robot's own frame G_i in W
  ControlOptions control;
  std::vector<SlipOptions> slips;  // simulation only
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
  robot_agent::FilterOptions filter;
  robot_agent::RendezvousOptions rendezvous;
  robot_agent::CooperationOptions cooperation;
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

// Parses and validates a scenario given as YAML text (a relative replay.dir is left as written).
// Throws ScenarioError with a one-line reason, whatever the text.
ScenarioOptions ParseScenario(const std::string& yaml_text);

}  // namespace mrslam::common
