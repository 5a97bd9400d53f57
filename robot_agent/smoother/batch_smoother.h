#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "common/se2.h"
#include "common/sensor_types.h"
#include "robot_agent/filters/odometry_calibration.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/levenberg_marquardt.h"
#include "robot_agent/smoother/normal_equations.h"

namespace mrslam::robot_agent::smoother {

// The maximum a posteriori estimate of several robots' paths and of their landmarks' paths from
// their odometry and readings, two uses:
// * the approximately ideal estimator against which the agents are judged (mrslam_batch
//   --reference, mrslam_batch --transform-reference), with the scenario's oracle knowledge
//   (scripts/batch/oracle_reference.h builds it so);
// * an agent's joint estimate of the transform to a peer at a rendezvous (cooperation.h), from
//   both robots' histories, each reading labelled by the filter's association and each
//   landmark's kinematics the filter's.
// As the reference: at every step, the maximum a posteriori
// estimate of the whole path so far of one robot, or of several robots at once, and of every
// seen landmark's path, from all their odometry and detections so far, with oracle knowledge a
// filter does not have: which landmark each detection is (the detections must carry identities)
// and each landmark's true kinematics (static or unicycle with its (v, w)). The models are the
// simulator's: x_t = f(x_{t-1}, u_t) + N(0, diag(noise.robot_process_var)),
// l_t = f(l_{t-1}; v, w) + N(0, diag(noise.landmark_process_var)) (static: l_t = l_{t-1}),
// z = (|p - x|, atan2(p - x) - heading) + N(0, diag(sd_r^2, sd_b^2)) for a landmark or robot at
// p, f the unicycle step. The first robot's first pose is known and anchors the frame (its own
// frame G_i); the first poses of the others in it are unknowns without a prior, so what places
// them is only what the data say (common landmarks, detections of each other). Solved by
// Gauss-Newton with Levenberg damping on the sparse normal equations, warm-started from the
// previous step's solution. A landmark's heading is started at its second sighting from the
// displacement between the two sightings. The odometry is calibrated as the filters calibrate it
// (filter.odometry_scale, odometry_turn_scale, odometry_lag_s; OdometryCalibration); a replayed
// data set's landmarks are static. With filter.outlier_gate_probability < 1, a reading whose
// whitened residual at the solution lies beyond that chi-square (2 dof) gate is left out and the
// problem solved again until the set of such readings stays the same (at most 10 rounds), as
// the filters ignore such readings. Add and Solve apart turn it into a smoother of a whole run
// (Path: every pose). EstimateOdometryCalibration: per robot three more unknowns, a speed
// factor s_v, a turn-rate factor s_w and a turn-rate bias b_w, the motion being the calibrated
// odometry's (s_v v, s_w w + b_w), with priors N(1, 0.1^2), N(1, 0.1^2), N(0, (0.05 rad/s)^2):
// a model of a real robot's systematic odometry errors that the fixed calibration leaves.
//
// Unequal steps: the robots of the set may hold different numbers of steps, robot r its steps
// 1..S_r (a peer's data up to the last step it was handed over; Add(r, step) appends robot r's
// next one, AddRobot adds a robot to the set). The unknowns are then robot r's poses
// x^r_0..x^r_{S_r} (the first robot's x^0_0 known), and a moving landmark's states
// l_a..l_b from the earliest step a at which any robot read it to the newest step b = max_r S_r
// any robot holds (a static one: one state); the factors are those above over exactly these
// unknowns: robot r's motion for t = 1..S_r, each landmark's motion for t = a+1..b, every
// reading of a landmark at its state at the reading's step, and a detection by robot r of robot
// q at step t only once q's pose x^q_t is held (t <= S_q; until then it waits). A unicycle step
// is a composition with a fixed increment, l_t = l_{t-1} * d with d = f(origin; v, w), so a chain
// read before its first state is started backwards by l_{t-1} = l_t * d^-1, and forward to b by
// l_t = l_{t-1} * d; its heading is started from the chord between its first two sightings at two steps,
// whichever comes first in time. With every S_r equal this is the problem above, built in the
// same order with the same arithmetic (Add(steps), or Add(r, steps[r]) for every r in the set's
// order). A detection of a robot counts only if that robot is in the set when it is added.
// Pure; not thread-safe.
class BatchSmoother {
 public:
  struct Kinematics {
    bool is_static = true;
    double v_mps = 0.0, w_radps = 0.0;
  };
  // A robot of the set: its scenario id (robot detections name it) and its first pose in the
  // frame (the first robot's anchors the frame; the others' are starting guesses).
  struct RobotStart {
    std::string id;
    common::Pose2 first_pose;
  };

  // A landmark whose label the kinematics do not list: its readings are left out, or it is taken
  // as static (a data set's landmarks, which all stand still).
  enum class Unlisted { kLeftOut, kStatic };

  // The readings' landmark_id fields are labels chosen by the caller, each landmark's
  // kinematics is given by label, and the robots' first poses are given (the first robot's
  // anchors the frame). options supply the step, the noise models, the odometry calibration and
  // the outlier gate only. Detections of robots of the set count from step
  // robot_detections_from_step on.
  BatchSmoother(const AgentOptions& options, const std::vector<RobotStart>& robots,
                std::map<int, Kinematics> kinematics, int robot_detections_from_step,
                Unlisted unlisted = Unlisted::kLeftOut);

  // One sensor step more per robot of the set, in the set's order, then Solve.
  void Process(const std::vector<common::SensorStep>& steps) {
    Add(steps);
    Solve();
  }
  void Process(const common::SensorStep& step) { Process(std::vector<common::SensorStep>{step}); }
  // One sensor step more per robot without solving: the new poses follow the odometry from the
  // last ones, a new landmark is placed from its first reading.
  void Add(const std::vector<common::SensorStep>& steps);
  // Robot r's next step (S_r + 1) alone, without solving.
  void Add(int r, const common::SensorStep& step);
  // Adds a robot to the set, holding its first pose only (a starting guess); returns its index.
  int AddRobot(const RobotStart& robot);
  // S_r: the last step robot r holds (0: its first pose only).
  int Steps(int r) const { return static_cast<int>(robots_.at(r).path.size()) - 1; }
  // The MAP estimate of everything added so far (warm-started from the current one).
  void Solve();
  // Starts from `previous`, a problem of some of the same robots and landmarks (after Add, before
  // Solve): each robot of the same id at its poses of the steps both hold and its correction, the
  // poses after them by its odometry; every landmark placed again from its readings seen from
  // those poses, then each at its label's there (same_landmark: label -> previous's label) at the
  // states of the steps both hold, the others by its kinematics from them, where both chains have
  // the same kinematics (and the previous one a heading started, if this one has).
  void StartFrom(const BatchSmoother& previous, const std::map<int, int>& same_landmark);
  // Estimates each robot's odometry factors and turn-rate bias too (call before Add).
  void EstimateOdometryCalibration() { estimate_calibration_ = true; }
  // Ends each solve once an iteration lowers the cost by less than tolerance x (1 + cost)
  // instead of running until the largest step is below 1e-7 (tolerance 0, the default). Where
  // the data leave a direction weakly determined, Gauss-Newton creeps along it for many
  // iterations that barely lower the cost. Stopping there leaves the solution off the minimum by
  // a small fraction of its uncertainty: the cost still to gain is a few times the last decrease,
  // and a cost excess c is a Mahalanobis distance sqrt(c) from the minimum.
  void SetRelativeCostTolerance(double tolerance) { relative_cost_tolerance_ = tolerance; }
  // Robot r's (s_v, s_w, b_w): (1, 1, 0) unless estimated.
  const Eigen::Vector3d& OdometryCorrection(int r) const { return robots_.at(r).correction; }
  // Robot r of the set (0: the first): its current pose and its first pose, in the frame.
  const common::Pose2& Pose(int r = 0) const { return robots_.at(r).path.back(); }
  const common::Pose2& FirstPose(int r) const { return robots_.at(r).path.front(); }
  // Robot r's (r >= 1) first-pose covariance at the current solution: the block of the inverse
  // of the Gauss-Newton information J^T J (the Laplace approximation of the posterior),
  // computed when asked.
  Eigen::Matrix3d FirstPoseCovariance(int r) const;
  // Robot r's current-pose covariance at the current solution, the same way (for the first
  // robot: relative to its known first pose).
  Eigen::Matrix3d PoseCovariance(int r = 0) const;
  // Robot r's every pose, from its first (step 0) to the last step added.
  const std::vector<common::Pose2>& Path(int r) const { return robots_.at(r).path; }
  // The current position of every landmark seen so far, with its identity.
  std::vector<std::pair<Eigen::Vector2d, int>> Landmarks() const;

 private:
  struct Chain {  // one landmark's states from its first sighting on (static: one state)
    int first_step = 0;
    Kinematics kinematics;
    std::vector<common::Pose2> states;
    bool heading_started = false;  // from the chord between sightings at two steps
  };
  struct Robot {
    std::string id;
    std::vector<common::Pose2> path;  // path[0]: the first pose
    filters::OdometryCalibration calibration;
    // motion[t - 1]: step t's calibrated odometry segments.
    std::vector<std::vector<filters::OdometryCalibration::Motion>> motion;
    Eigen::Vector3d correction{1.0, 1.0, 0.0};  // (s_v, s_w, b_w)
  };
  // Step t's motion in the robot's frame under `correction`: x_t = Compose(x_{t-1}, increment)
  // (a unicycle step is one), the corrected segments composed.
  static common::Pose2 Increment(const Robot& robot, int t, const Eigen::Vector3d& correction);
  struct Reading {
    int step = 0, robot = 0;  // who read it, when
    int landmark_id = -1;     // a landmark, or -1: robot `seen` of the set
    int seen = -1;
    double range_m = 0.0, bearing_rad = 0.0;
    bool inlier = true;  // within the outlier gate at the last solution
  };

  common::Pose2 StepLandmark(const common::Pose2& l, const Kinematics& k) const;
  // Robot r's next pose from its odometry.
  void AppendPose(int r, const common::SensorStep& step);
  // Robot r's readings of its newest step.
  void AddReadings(int r, const common::SensorStep& step);
  void AddLandmarkReading(int r, int t, const common::LandmarkDetection& d);
  // Starts, or extends back, the chain of the landmark z reads (from the reader's pose there).
  void PlaceFrom(const Reading& z);
  // StartFrom for one landmark: its chain at `before`'s states where they share steps.
  void StartChainFrom(Chain* chain, const Chain& before) const;
  // The newest step any robot holds, and every moving chain's states up to it.
  int Horizon() const;
  void ExtendChains();
  void ExtendChain(Chain* chain, int horizon) const;
  // A moving chain's states back to step t (inverse unicycle steps).
  void PrependChain(Chain* chain, int t) const;
  // Restarts a moving chain from its two sightings (at seen_at, its state there, and at t, point).
  void StartHeading(Chain* chain, int seen_at, int t, const Eigen::Vector2d& point) const;
  static int StateIndex(const Chain& chain, int t);  // of a landmark's state at step t
  // A reading whose target is held (a robot detection waits for the seen robot's pose).
  bool Usable(const Reading& z) const {
    return z.landmark_id >= 0 || z.step < static_cast<int>(robots_[z.seen].path.size());
  }
  // Gauss-Newton with Levenberg damping over the inlying readings.
  void SolveOnce();
  // The unknowns' columns: every robot's poses (the first robot's from step 1, the others' from
  // their first pose), then every chain's states in id order, then (if estimated) every robot's
  // correction.
  struct Layout {
    int cols = 0, correction_base = -1;
    std::vector<int> robot_base;
    std::map<int, int> chain_col;      // by landmark id
    int RobotCol(int r, int t) const;  // -1: the first robot's first pose, known
    int CorrectionCol(int r) const { return correction_base < 0 ? -1 : correction_base + 3 * r; }
  };
  Layout MakeLayout() const;
  // The normal equations of every factor's whitened residual at the current estimate (the cost
  // only without jacobians); the Jacobian's pattern, structural zeros kept, depends on the
  // structure only, so the ordering of H is computed once per solve.
  void BuildRows(const Layout& layout, NormalEquations* rows) const;
  NormalEquations Equations(const Layout& layout, bool jacobians) const;
  // The unknowns moved by sign * delta.
  void Apply(const Layout& layout, const Eigen::VectorXd& delta, double sign);
  // A reading's target (landmark or robot position) and its residual z - h, whitened, at the
  // current solution.
  Eigen::Vector2d Target(const Reading& z) const;
  Eigen::Vector2d WhitenedResidual(const Reading& z) const;
  // The 3x3 block of (J^T J)^-1 at the current solution at robot r's pose of step t (t < 0: its
  // current pose); infinite where the information is singular.
  Eigen::Matrix3d PoseBlockCovariance(int r, int t) const;
  // Marks the readings within the outlier gate at the current solution; true if any changed.
  bool UpdateInliers();

  double dt_s_;
  FilterOptions filter_;  // the odometry calibration and the outlier gate
  Unlisted unlisted_;
  bool estimate_calibration_ = false;
  double relative_cost_tolerance_ = 0.0;
  Eigen::Vector3d robot_var_, landmark_var_;
  double var_r_, var_b_;
  int robot_detections_from_step_;
  std::map<int, Kinematics> kinematics_;  // by landmark id
  std::vector<Robot> robots_;
  std::map<int, Chain> chains_;
  std::vector<Reading> readings_;
};

}  // namespace mrslam::robot_agent::smoother
