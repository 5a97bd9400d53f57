#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/graph_factors.h"
#include "robot_agent/smoother/levenberg_marquardt.h"
#include "robot_agent/smoother/normal_equations.h"
#include "robot_agent/smoother/odometry_preintegration.h"

namespace mrslam::robot_agent::smoother {

// The maximum a posteriori estimate of several robots' paths, their static landmarks and their
// odometry corrections from the raw measurements one agent holds of them (its own and those
// shared with it, docs/cooperation.md), in the agent's own frame (docs/smoother.md, "The joint
// graph"). Pure; not thread-safe.
//
// The robots: robots[0] is the agent's own, its first pose known (it anchors the frame); every
// other robot r has its first pose in the agent's frame as an unknown (T(G_self <- G_r) =
// x^r_0 * first_pose_r^-1, its frame). A robot is placed once a mutual detection links it to a
// placed robot q: q's scan reads r at step t and r's reads q at a step within
// rendezvous.window_steps of t (the pair nearest in time, then the earliest); r's pose at t
// starts at q's pose composed with the reading, its heading from r's bearing to q, and r's
// other poses follow its odometry from there. Robots never so linked stay out (nothing in the
// data fixes their frames).
//
// Keyframes per robot: its first pose, every step with a reading (of a landmark, or of a robot
// of the set), every step at which a robot of the set reads it, every
// filter.smoother.max_keyframe_gap_steps steps and its last step held. Factors, each a whitened
// residual as KeyframeGraph's:
// * odometry between consecutive keyframes of a robot under its correction c_r = (s_v, s_w,
//   b_w) (OdometryIncrement, preintegrated: OdometryPreintegration; covariance accumulated per step from
//   noise.robot_process_var, fixed at the configured calibration), and the correction's prior N((1, 1, 0),
//   diag(filter.smoother.*_sd^2)) per robot;
// * a landmark reading (range, bearing) of landmark j from keyframe x: r = W (z - h(x, p_j)),
//   Huber loss of width huber_k, left out while its whitened squared norm exceeds the chi-square
//   2 dof quantile of reading_gate_probability (re-decided after each solve, at most 5 rounds).
//   Landmarks are static. Their labels are the origin's tracks, each robot's apart, unless the
//   sensor reports identities (sensors.lidar.report_identity): then a label is the identity
//   + 1 and the same label from two robots is one landmark;
// * a reading of robot q by robot r at step t: the same residual with q's position at t as the
//   point, so it ties x^r_t and x^q_t.
// Solved by Levenberg-Marquardt (LevenbergMarquardt) to convergence (at most 100 iterations per
// round) from the starting values above: loosely (steps below 1e-7) while the gate's decisions
// change, then tightly (below 1e-9) with them, again while they change. A factor enters once: the logs hold each
// (origin, step) once, whoever relayed it. Frame covariances: the marginal of x^r_0 from the information at the
// solution (the last iteration's factorization when it serves), carried through the composition with first_pose_r^-1.
class JointGraph {
 public:
  // One robot's raw measurements: its steps 1..n in order (steps[i] is step i + 1), each landmark
  // reading labelled (landmark_id >= 1), each robot reading naming the robot seen.
  struct RobotLog {
    std::string id;
    common::Pose2 first_pose;  // in its own frame
    const std::vector<common::SensorStep>* steps = nullptr;
  };

  // robots[0]: the agent's own. Builds the graph and its starting values; Solve solves it.
  JointGraph(const AgentOptions& options, const std::vector<RobotLog>& robots);
  // Starts from `previous`, a graph of the same robots' logs as they were earlier (each a prefix
  // of the one now, robots new since then may be added): every robot it placed is placed, its
  // keyframes up to the step previous was solved to start at previous's poses (a keyframe new
  // among them, by its odometry from the one before), its correction and the landmarks at
  // previous's, and Solve goes on from that step. Call before Solve.
  void WarmStart(const JointGraph& previous);
  // Solves over the growing horizon; the last horizon (to_convergence) to convergence, or else as
  // the others, a few iterations and one decision of the gate (a warm-started update, cheaper).
  void Solve(bool to_convergence = true);

  int Robots() const { return static_cast<int>(robots_.size()); }
  bool Placed(int r) const { return robots_.at(r).placed; }
  // Robot r's keyframes: their steps and poses in the agent's frame (empty unless placed).
  std::vector<std::pair<int, common::Pose2>> Path(int r) const;
  // T(G_self <- G_r) and its covariance (r placed; robot 0: the identity, zero covariance).
  common::Pose2 Frame(int r) const;
  Eigen::Matrix3d FrameCovariance(int r) const;
  // Readings left out by the gate at the solution, and readings in the graph.
  int Outliers() const { return CountReadings(true); }
  int Readings() const { return CountReadings(false); }

 private:
  struct Observation {
    int landmark = -1;  // index into landmarks_, or -1: a reading of robot `seen`
    int seen = -1;
    double range_m = 0.0, bearing_rad = 0.0;
    bool inlier = true;
  };
  struct Keyframe {
    int step = 0;
    common::Pose2 pose;                      // in the agent's frame once placed
    std::vector<std::vector<Motion>> steps;  // the odometry since the previous keyframe
    Eigen::Matrix3d whitening = Eigen::Matrix3d::Identity();
    std::vector<Observation> observations;
    mutable OdometryPreintegration odometry;  // the odometry factor's increment (a cache)
  };
  struct Robot {
    std::string id;
    common::Pose2 first_pose;
    bool placed = false;
    int active = 0;  // the keyframes in the problem: the first `active` (0: not placed)
    std::vector<Keyframe> keyframes;
    std::map<int, int> keyframe_at;  // step -> index into keyframes
    Eigen::Vector3d correction{1.0, 1.0, 0.0};
    int pose_col = -1, correction_col = -1;  // columns (the first pose of robot 0 has none)
  };
  // A mutual detection: robot `by` reads robot `of` at step_by, `of` reads `by` at step_of.
  struct Mutual {
    int by = 0, of = 0, step_by = 0, step_of = 0;
  };

  void BuildKeyframes(const std::vector<RobotLog>& logs);
  std::vector<int> KeyframeSteps(const std::vector<RobotLog>& logs, int r) const;
  void AddObservations(const std::vector<RobotLog>& logs, int r);
  int LandmarkIndex(int r, int label);
  // Places the robots that mutual detections up to step `horizon` link to placed ones; true if any.
  bool Place(int horizon);
  bool PlaceFrom(const Mutual& m);
  // Takes the placed robots' keyframes up to `horizon` into the problem, each started from the
  // one before by its odometry.
  void Extend(int horizon);
  void Activate(int horizon);
  bool TargetActive(const Observation& o, int step) const;
  const Observation* ReadingOf(int r, int step, int seen) const;
  void StartLandmarks();
  void MakeLayout();
  int PoseCol(int r, int k) const;
  NormalEquations Equations(bool jacobians) const;
  void AddOdometryRows(int r, NormalEquations* rows) const;
  void AddObservationRows(int r, NormalEquations* rows) const;
  void AddCorrectionPrior(int r, NormalEquations* rows) const;
  Eigen::Vector2d Target(const Observation& o, int step) const;
  void Step(const Eigen::VectorXd& delta);
  bool UpdateInliers();
  int CountReadings(bool only_outliers) const;

  static constexpr double kRidge = 1e-9;
  static constexpr double kSolveEveryS = 30.0;
  static constexpr int kRounds = 5, kIterations = 100, kHorizonIterations = 3;

  int gap_steps_, window_steps_;
  int last_step_ = 0;
  int solved_to_ = 0;  // the horizon solved so far (WarmStart: the previous graph's)
  bool identities_;
  double huber_k_, gate_;
  Eigen::Vector3d robot_var_, prior_w_;
  Eigen::Vector2d z_w_;
  AgentOptions options_;
  std::vector<Robot> robots_;
  std::vector<Eigen::Vector2d> landmarks_;
  std::vector<bool> landmark_started_;
  // (the labelling robot's id, or empty for an identity; label) -> index
  std::map<std::pair<std::string, int>, int> landmark_index_;
  std::vector<int> landmark_col_;
  int cols_ = 0;
  mutable std::size_t triplets_ = 0;  // of the last normal equations built: the next one's reserve
  // The information matrix at the solution, factorized: the last iteration's (linearized where
  // it started, a step of negligible length from the solution: LmResult::InformationUsable), or
  // afresh when that one cannot serve; null if it failed.
  std::shared_ptr<const Factorization> information_;
};

}  // namespace mrslam::robot_agent::smoother
