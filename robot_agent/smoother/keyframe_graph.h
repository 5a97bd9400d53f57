#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "common/se2.h"
#include "robot_agent/filters/odometry_calibration.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/levenberg_marquardt.h"
#include "robot_agent/smoother/normal_equations.h"
#include "robot_agent/smoother/odometry_preintegration.h"

namespace mrslam::robot_agent::smoother {

// A fixed-lag smoother of one robot's keyframe poses, its static landmarks and its odometry
// calibration, in the robot's own frame (docs/smoother.md). Pure; not thread-safe.
//
// Unknowns: the poses x_k of the keyframes in the window (the first keyframe of the run is the
// known start pose), each static landmark's position p_j (by track id), and the odometry
// correction c = (s_v, s_w, b_w): the robot moves at (s_v v, s_w w + b_w) for the calibrated
// odometry's (v, w). Factors, each a whitened residual:
// * odometry between consecutive keyframes a, b: e = Between(x_a, x_b) - Delta(c), heading
//   wrapped, Delta the composition of the unicycle steps of the corrected odometry segments of
//   the steps in between; covariance Sigma accumulated over those steps,
//   Sigma_i = J Sigma_{i-1} J^T + Q (J = d Compose(Delta_{i-1}, delta_i) / d Delta_{i-1}, Q the
//   per-step noise.robot_process_var taken in the keyframe's frame, exact when its x and y
//   variances are equal), r = L^-1 e with Sigma = L L^T;
// * a reading (range, bearing) of landmark j at keyframe k: r = W (z - h(x_k, p_j)), bearing
//   wrapped, W = diag(1/sd_r, 1/sd_b), under a Huber loss of width huber_k (iteratively
//   reweighted: a block of whitened norm s > k is scaled by sqrt(k / s)); a reading whose s^2
//   exceeds the chi-square 2 dof quantile of reading_gate_probability at the solution is left
//   out, and taken back when it falls within again (re-decided at every solve);
// * a moving landmark (a track the caller names with its unicycle (v, w)) has a state
//   (x, y, heading) at every keyframe from its first reading in the window to its last; between
//   consecutive states a and b, e = Between(s_a, s_b) - Delta, Delta the n steps of the unicycle
//   with (v, w), covariance accumulated as the odometry's from noise.landmark_process_var; its
//   readings are factors on the position of the state at their keyframe; a chain's first state
//   has a weak prior (sd 1000 rad) on the heading it starts with (from the caller), so that it
//   is defined before the motion makes it observable;
// * the prior left by marginalization, 0.5-free quadratic form
//   (x - x0)^T H_p (x - x0) + 2 g_p^T (x - x0) over the variables it names, x0 the values at
//   marginalization (heading differences wrapped); it starts as the calibration prior
//   N((1, 1, 0), diag(calibration_prior_sd^2)).
// Solve: Levenberg-Marquardt on the sparse normal equations (J^T J + H_p), warm-started from
// the last solution, at most max_iterations iterations (a solution left short of convergence is
// carried on at the next keyframe), stopping when the step or the relative decrease of the cost
// is negligible; then the gate re-decided and solved again while the set of outliers changes
// (at most 3 rounds).
// When the window holds more than window_keyframes keyframes, the oldest is marginalized: the
// factors touching it and the prior are linearized at the current estimate into H, g over the
// variables involved, and the oldest pose eliminated by the Schur complement
// H' = H_rr - H_rm H_mm^-1 H_mr, g' = g_r - H_rm H_mm^-1 g_m (m: the oldest pose and the moving
// landmarks' states at it); its readings and odometry leave the window and its pose joins the
// fixed history (Path).
// Marginal covariances are blocks of (J^T J + H_p)^-1 (Laplace approximation), from the
// factorization of the solve's last iteration (linearized where that iteration started, a step
// of at most a few millimetres from the solution once warm-started; factorized afresh when that
// iteration was damped or the gate changed after it):
// the newest pose's, the correction's and the moving landmarks' at every solve, a static
// landmark's when it is read (in between it keeps the last, which errs on the large side as
// information only accrues).
class KeyframeGraph {
 public:
  using Motion = filters::OdometryCalibration::Motion;
  struct Reading {
    std::uint32_t track = 0;
    double range_m = 0.0, bearing_rad = 0.0;
  };
  struct Landmark {
    std::uint32_t track = 0;
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  };
  // A moving landmark's unicycle kinematics and its heading when its track starts.
  struct MoverModel {
    double v_mps = 0.0, w_radps = 0.0;
    double start_heading = 0.0;
  };
  struct Mover {
    std::uint32_t track = 0;
    common::Pose2 state;  // at the newest keyframe with a state
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
    int step = 0;  // of that keyframe
  };

  KeyframeGraph(const AgentOptions& options, const common::Pose2& start);

  // Writes or reads back the graph: keyframes (the window and those marginalized), pending
  // motion, landmarks, movers, the marginalization prior and the covariances last computed.
  void Io(common::Archive& ar);

  // One step's calibrated odometry segments, pending until the next keyframe.
  void AddMotion(const std::vector<Motion>& segments);
  // A keyframe at `step` from the pending motion, with its readings; the pose starts at the
  // odometry's prediction. Marginalizes the oldest keyframe when the window is full.
  void AddKeyframe(int step, const std::vector<Reading>& readings);
  // The tracks whose readings are factors: static landmarks, and moving ones with their models;
  // the others' readings wait.
  void SetTracks(std::set<std::uint32_t> static_tracks, const std::map<std::uint32_t, MoverModel>& movers) {
    Settle();
    static_tracks_ = std::move(static_tracks);
    moving_tracks_.clear();
    for (const auto& [track, model] : movers) {
      mover_models_[track] = model;
      moving_tracks_.insert(track);
    }
    DropStoppedChains();
  }
  // Replaces the track of every reading labelled `from` by `to` in the keyframes from
  // `from_step` on (a re-association).
  void Relabel(int from_step, const std::map<std::uint32_t, std::uint32_t>& from_to);
  // Moves the keyframes from the one at `from_step` on by the rigid transform `correction`
  // (applied on the left) and cuts the odometry factor into that keyframe: the robot was moved
  // in a way its odometry did not see.
  void CutAndMove(int from_step, const common::Pose2& correction);
  // Solves the window, then computes the covariances; when the prior's variables have moved
  // more than relinearize_threshold from where it was linearized, a relinearization is due.
  void Solve();
  // Does a relinearization that is due (Relinearize): work whose result serves the next step
  // only, so a driver may do it between steps; every change to the graph does it first. With
  // relinearize_delay_steps, starts it on a thread of its own instead (applied by AddKeyframe).
  void Settle();

  // The newest pose (the last keyframe's composed with the pending motion) and its marginal
  // covariance, the correction's uncertainty included.
  common::Pose2 Pose() const;
  Eigen::Matrix3d PoseCovariance() const;
  int KeyframeStep() const { return window_.back().step; }
  const common::Pose2& KeyframePose() const { return window_.back().pose; }
  // The landmarks the caller names static now (SetTracks), with their last covariances.
  std::vector<Landmark> Landmarks() const;
  // Each moving landmark's newest state in the window.
  std::vector<Mover> Movers() const;
  // A mover's state predicted by its model to `step`, with the covariance grown by the model's
  // noise: F P F^T + Sigma_n over the n steps.
  struct Prediction {
    common::Pose2 state;
    Eigen::Matrix3d covariance;
  };
  Prediction PredictMover(const Mover& mover, int step) const;
  // The cost the window's factors reach with `track` moving by `model` (its start heading kept):
  // a copy of the graph, every reading taken in under the Huber loss (no gate, so that no model
  // gains by leaving readings out), solved from the current estimate by at most
  // kTrialIterations iterations. This graph is unchanged.
  static constexpr int kTrialIterations = 5;
  double TrialCost(std::uint32_t track, double v_mps, double w_radps) const;
  // The number of states of the track's chain in the window.
  int ChainStates(std::uint32_t track) const;
  // The last model SetTracks gave each track once moving.
  const std::map<std::uint32_t, MoverModel>& MoverModels() const { return mover_models_; }
  const Eigen::Vector3d& Correction() const { return correction_; }
  // Every keyframe's step and pose, the marginalized ones as they were when they left.
  std::vector<std::pair<int, common::Pose2>> Path() const;
  // The maximum a posteriori estimate of every keyframe's pose of the run: every keyframe's
  // factors (none marginalized; the prior is the calibration's alone) solved at once, started
  // from the current estimates, to convergence. The final map product of a run.
  std::vector<std::pair<int, common::Pose2>> SmoothAll() const;
  // Every keyframe's pose as it stands: the marginalized ones as they left the window, then the
  // window's.
  std::vector<common::Pose2> KeyframePoses() const;
  // The readings of the newest keyframe and whether each is within the gate at the solution.
  std::vector<std::pair<Reading, bool>> NewestReadings() const;
  int WindowSize() const { return static_cast<int>(window_.size()); }
  // Keyframes marginalized so far (held in the fixed history for SmoothAll).
  int HistorySize() const { return static_cast<int>(history_.size()); }
  // Whether a relinearization is under way on its thread (relinearize_delay_steps).
  bool Relinearizing() const { return relinearizing_.has_value(); }

  // The bytes of what the graph holds beyond the object itself (SlamFilter::EstimatorBytes: the
  // elements of its containers): the window's and the history's keyframes (KeyframeBytes each),
  // the pending motion, the landmarks, the tracks, the movers' states and models, the priors
  // (variables, linearization points, H_p, g_p) and the covariances last computed. Grows by one
  // keyframe's bytes per marginalized keyframe; the rest follows the window, the map and the
  // movers, bounded while they are; while a relinearization runs, the two copies it holds too.
  std::size_t EstimatorBytes() const;
  // What one keyframe holds, its pose, odometry (per step a vector of segments), readings and
  // preintegrated odometry: sizeof(Keyframe) + steps sizeof(std::vector<Motion>) + segments
  // sizeof(Motion) + readings sizeof(StoredReading), `segments` counted over all its steps
  // (x86-64: 520 + 24 + 24 + 32).
  static std::size_t KeyframeBytes(int steps, int segments, int readings);

 private:
  struct StoredReading {
    Reading z;
    bool inlier = true;
  };
  struct Keyframe {
    int step = 0;
    common::Pose2 pose;
    bool fixed = false;                      // the run's first pose
    bool has_odometry = false;               // a factor from the previous keyframe
    bool odometry_cut = false;               // cut by CutAndMove: none even in SmoothAll
    std::vector<std::vector<Motion>> steps;  // the odometry since the previous keyframe, per step
    Eigen::Matrix3d odometry_whitening = Eigen::Matrix3d::Identity();  // L^-1
    std::vector<StoredReading> readings;
    // The odometry factor's increment, evaluated at every solve (a cache: not written).
    mutable OdometryPreintegration odometry;

    void Io(common::Archive& ar) {
      ar(step, pose, fixed, has_odometry, odometry_cut, steps, odometry_whitening, readings);
    }
  };
  // A variable: a keyframe pose (by step), a landmark (by track) or the correction.
  struct Var {
    enum Kind : std::uint8_t { kPose, kLandmark, kMover, kCorrection } kind = kPose;
    std::int64_t key = 0;  // a pose's step, a landmark's track, MoverKey for a mover's state
    bool operator<(const Var& o) const { return kind != o.kind ? kind < o.kind : key < o.key; }
    bool operator==(const Var& o) const { return kind == o.kind && key == o.key; }
  };
  struct Prior {
    std::vector<Var> vars;
    std::vector<Eigen::VectorXd> x0;
    Eigen::MatrixXd h;
    Eigen::VectorXd g;

    void Io(common::Archive& ar) { ar(vars, x0, h, g); }
  };
  struct Layout {
    std::map<Var, int> col;
    int cols = 0;
    int Col(const Var& v) const {
      const auto it = col.find(v);
      return it == col.end() ? -1 : it->second;
    }
  };
  using Rows = NormalEquations;
  static std::int64_t MoverKey(std::uint32_t track, int step) {
    return (static_cast<std::int64_t>(track) << 32) | static_cast<std::uint32_t>(step);
  }
  static std::uint32_t MoverTrack(std::int64_t key) { return static_cast<std::uint32_t>(key >> 32); }
  static int MoverStep(std::int64_t key) { return static_cast<int>(key & 0xffffffff); }

  static int Dim(const Var& v) { return v.kind == Var::kLandmark ? 2 : 3; }
  // EstimatorBytes' parts: motion per step, and one keyframe (KeyframeBytes).
  static std::size_t MotionBytes(const std::vector<std::vector<Motion>>& steps);
  static std::size_t HeldBytes(const Keyframe& kf);
  common::Pose2 MoverIncrement(const MoverModel& model, int steps) const;
  Eigen::Matrix3d MoverWhitening(const MoverModel& model, int steps) const;
  bool MoverReading(const StoredReading& r, int step) const {
    return r.inlier && moving_tracks_.count(r.z.track) > 0 && movers_.count(MoverKey(r.z.track, step)) > 0;
  }
  void StartMovers();
  // Removes the states of tracks no longer moving that the prior does not hold.
  void DropStoppedChains();
  Eigen::VectorXd Value(const Var& v) const;
  void SetValue(const Var& v, const Eigen::VectorXd& value);
  Eigen::VectorXd Difference(const Var& v, const Eigen::VectorXd& x0) const;  // x - x0, wrapped
  const Keyframe* FindKeyframe(int step) const;
  Keyframe* FindKeyframe(int step);
  bool Active(const StoredReading& r) const { return r.inlier && static_tracks_.count(r.z.track) > 0; }
  // The variables of the whole window (oldest 0), or of the oldest `oldest` keyframes' factors
  // and the prior, those keyframes' poses and mover states first.
  std::vector<Var> Variables(int oldest) const;
  Layout MakeLayout(const std::vector<Var>& vars) const;
  void StartLandmarks();
  // The whitened rows of the factors (oldest > 0: those touching the oldest `oldest` keyframes).
  void BuildRows(const Layout& layout, int oldest, Rows* rows) const;
  void AddOdometryRows(const Layout& layout, const Keyframe& previous, const Keyframe& kf, Rows* rows) const;
  void AddReadingRows(const Layout& layout, const Keyframe& kf, Rows* rows) const;
  void AddMoverRows(const Layout& layout, std::uint32_t track, int from_step, int to_step, Rows* rows) const;
  // The prior's terms: H_p at the layout's columns, its gradient at the current values, its cost.
  void AddPrior(const Layout& layout, Rows* rows) const;
  Rows Equations(const Layout& layout, int oldest, bool jacobians) const;
  double SolveOnce();
  void SolveWithGate();  // SolveOnce, then again while the gate's decisions change
  bool UpdateInliers();
  void Marginalize();  // starts the new landmarks and mover states, then MarginalizeOldest
  // Eliminates the oldest `count` keyframes' poses and mover states at once (a sparse Schur
  // complement) into the prior; every variable their factors touch started.
  void MarginalizeOldest(int count);
  // The largest component of x - x0 over the prior's variables.
  double PriorDrift() const;
  // The whole run solved to convergence, then the window's prior rebuilt at that solution by
  // marginalizing the history again (relinearize_threshold): at once, or started now on a thread
  // and applied at the first keyframe relinearize_delay_steps on (Relinearization).
  void Relinearize();
  // The whole run as it stands, to be solved.
  std::shared_ptr<KeyframeGraph> WholeToSolve(const KeyframeGraph& at, std::size_t history) const;
  // Takes the whole run solved when the relinearization fell due: the keyframes and landmarks
  // added since are appended, moved by the rigid motion that takes the newest keyframe it holds
  // from here to its solution, the rest of the state since kept, and the history marginalized
  // again at that solution down to the window.
  void Adopt(KeyframeGraph solved);
  // Gives `solved` this graph's covariances, those of the states Adopt moves by `shift` turned
  // by its rotation as they are: the newest pose's (with the correction's), and each landmark's
  // and mover's that `solved` does not hold yet; the others as they were.
  void TurnCovariances(const common::Pose2& shift, KeyframeGraph* solved) const;
  // At a keyframe of `step`: applies the relinearization under way once its step has come (waits
  // for it if need be), or drops it when a keyframe it holds was relabelled or moved since.
  void ApplyRelinearization(int step);
  // A keyframe from `from_step` on relabelled or moved: the relinearization under way is stale if
  // it holds that keyframe.
  void MarkRelinearizationStale(int from_step);
  // A copy with every keyframe in the window, none marginalized (the prior the calibration's
  // alone), solved to convergence by SolveWithGate.
  KeyframeGraph Whole() const;
  // Makes this graph that copy: the history moved into the window.
  void MakeWhole();
  std::vector<Var> CovarianceTargets(const std::vector<Var>& vars) const;
  // The information matrix (with the ridge) at the solution, factorized.
  std::shared_ptr<const Factorization> Information(const std::vector<Var>& vars, const Layout& layout) const;
  void ComputeCovariances();

  static constexpr double kRidge = 1e-9;  // added to the information's diagonal

  double dt_s_;
  int window_keyframes_;
  int max_iterations_;
  double relinearize_threshold_;
  int relinearize_delay_steps_;
  bool relinearize_due_ = false;
  // A relinearization under way (relinearize_delay_steps): the graph when it fell due without its
  // history (of which it had the first `history`), the first keyframe step at which it is applied,
  // whether a keyframe it holds has been relabelled or moved since, the solve on its thread, and
  // the bytes the two copies hold (that graph, and the whole run being solved) while it runs.
  struct Relinearization {
    std::shared_ptr<const KeyframeGraph> at;
    std::size_t history = 0;
    int apply_at = 0;
    bool stale = false;
    std::size_t bytes = 0;
    std::shared_future<std::shared_ptr<KeyframeGraph>> solved;
  };
  std::optional<Relinearization> relinearizing_;
  // Starts the solve of the whole run as `at` and the first `history` keyframes of the history
  // were, on a thread of its own.
  void StartRelinearization(std::shared_ptr<const KeyframeGraph> at, std::size_t history, int apply_at);
  // The graph's state (Io without the relinearization under way), and that relinearization.
  void IoState(common::Archive& ar);
  void IoRelinearization(common::Archive& ar);
  double huber_k_, gate_;
  Eigen::Vector3d robot_var_, landmark_var_;
  Eigen::Vector2d z_w_;
  std::deque<Keyframe> window_;
  std::vector<Keyframe> history_;             // the marginalized keyframes, as they left
  std::size_t history_bytes_ = 0;             // HeldBytes summed over history_
  std::vector<std::vector<Motion>> pending_;  // the motion since the last keyframe
  std::map<std::uint32_t, Eigen::Vector2d> landmarks_;
  std::set<std::uint32_t> static_tracks_;
  std::map<std::uint32_t, MoverModel> mover_models_;  // the last model of every track once moving
  std::set<std::uint32_t> moving_tracks_;             // moving now
  std::map<std::int64_t, common::Pose2> movers_;      // moving landmarks' states, by MoverKey
  std::map<std::int64_t, double> chain_starts_;       // states under the weak heading prior: its mean
  Eigen::Vector3d correction_{1.0, 1.0, 0.0};
  Prior prior_;
  Prior calibration_prior_;  // the prior at the start
  // At the last solution: the joint covariance of the newest keyframe pose and the correction,
  // and each landmark's.
  Eigen::Matrix<double, 6, 6> pose_correction_cov_ = Eigen::Matrix<double, 6, 6>::Zero();
  std::map<std::uint32_t, Eigen::Matrix2d> landmark_cov_;
  std::map<std::int64_t, Eigen::Matrix3d> mover_cov_;  // of each chain's newest state
  // The information matrix of the last solve's last iteration, factorized, and its variables;
  // null when it cannot serve the covariances.
  std::shared_ptr<const Factorization> information_;
  std::vector<Var> information_vars_;
};

}  // namespace mrslam::robot_agent::smoother
