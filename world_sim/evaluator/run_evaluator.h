#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "common/config/scenario_options.h"
#include "common/sensor_types.h"
#include "world_sim/evaluator/delivery_timing.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/evaluator/robot_estimate.h"
#include "world_sim/evaluator/robot_scorer.h"
#include "world_sim/evaluator/truth_path.h"

namespace mrslam::evaluator {

// One pose of an agent's final trajectory (its own frame).
struct FinalPose {
  std::uint32_t step = 0;
  double time_s = 0.0;
  common::Pose2 pose;
};

// Scores a run as it goes: the per-step metrics (errors in each robot's own frame, through the
// true frame pose) and the run summary of docs/metrics.md; writes metrics.csv, TUM
// trajectories, tracks.csv (everything in the first robot's frame, for plots) and view.jsonl
// (the run step by step for mrslam_view --run) step by step, and summary.json at the end. A step
// is shown once its truth and every robot's estimate of it are in (or later ones show they will
// not come), scored once shown and every robot's odometry of it is in (or a later one), robots in
// order, so that the files do not depend on the order in which the data arrived; then it is let
// go, so that the memory held does not grow with the run: per step only each robot's true pose in
// its frame (for its final trajectory) and a few numbers. Pure: no DDS.
class RunEvaluator {
 public:
  // Creates out_dir and its files at once.
  RunEvaluator(const common::ScenarioOptions& scenario, const std::string& out_dir);

  // written_ns: when world_sim wrote the message (DDS's source timestamp, ns since the Unix
  // epoch; 0 unknown), for the delivery figures (DeliveryTiming).
  void AddTruth(const common::GroundTruth& truth, std::int64_t written_ns = 0);
  // A second estimate of a step already scored (an agent that came back and published it again)
  // is left out.
  void AddEstimate(const std::string& robot_id, const RobotEstimate& estimate);
  // A robot's odometry of a step; written_ns: when its sensor step was written.
  void AddOdometry(const std::string& robot_id, const common::Odometry& odometry, std::int64_t written_ns = 0);
  // A chunk (0..chunks-1) of a robot's final trajectory.
  void AddFinalTrajectory(const std::string& robot_id, std::uint32_t chunk, std::vector<FinalPose> poses);

  // True once the truth, every robot's estimate and odometry of the last step N and every final
  // trajectory chunk announced are in. Steps lost before them (dropped from a writer's history
  // when a reader fell too far behind) are not waited for: they are counted (TruthStepsLost, the
  // summary's *_lost figures) and the run is scored without them.
  bool Complete() const;
  // Truth steps of 0..N that did not come.
  std::size_t TruthStepsLost() const;
  // What is still missing (for a timeout message).
  std::string Missing() const;
  // How many distinct messages were taken in so far: it grows only with something new, not with a
  // message sent again (a writer's history replayed).
  std::size_t Taken() const { return taken_; }
  // Steps, estimates and times held, not yet scored, shown or timed (a run gone out of step
  // holds more).
  std::size_t Pending() const;

  // Scores what is still held (steps whose data did not all come), the final trajectories, and
  // writes summary.json. Returns the summary.
  nlohmann::json Finish(double wall_seconds);

 private:
  // One robot's part of the run.
  struct RobotRun {
    common::Pose2 frame;  // G_i in W
    std::optional<RobotScorer> scorer;
    std::map<std::uint32_t, RobotEstimate> pending;      // received, not yet scored
    std::map<std::uint32_t, common::Odometry> odometry;  // received, not yet used
    std::uint32_t newest_estimate = 0;                   // the newest step received
    std::uint32_t newest_odometry = 0;
    std::size_t estimates = 0, odometry_steps = 0;  // received
    bool last_step_in = false;
    std::uint32_t final_chunks_announced = 0;
    std::optional<RobotEstimate> last;  // the newest scored
    std::vector<double> step_cpu_ms;
    // What the agent's estimator held (RobotEstimate::estimator_bytes): at the newest step scored,
    // and the most over the run.
    std::uint64_t estimator_bytes_final = 0, estimator_bytes_max = 0;
    std::map<int, std::uint32_t> reached;  // true landmarks ever within its reach: the first step
    TruthPath truth_own;                   // its true pose in G_i by step
    double online_sum_sq = 0.0;            // its online path as a final trajectory
    std::size_t online_count = 0;
    std::map<std::uint32_t, std::vector<FinalPose>> final_chunks;
    std::ofstream tum_estimate, tum_truth, tum_final;
  };

  void Start(const common::GroundTruth& truth0);
  // Shows and scores whatever is complete (finishing: everything held), then lets go of the
  // truth no one needs any more.
  void Advance(bool finishing);
  // The steps held: those of the truth and of the robots' estimates not yet scored.
  std::set<std::uint32_t> HeldSteps() const;
  void WriteViewSteps(bool finishing);
  void ScoreSteps(bool finishing);
  void ScoreStep(const std::string& id, RobotRun* robot, const RobotEstimate& est, const common::Odometry* odo);
  void WriteStep(const std::string& id, const RobotEstimate& estimate, const StepScore& score, RobotRun* robot);
  // The landmarks within the reach of the robot (the whole run) or of a robot whose frame it
  // knows at the end: over that robot's whole run, or (reachable_only) over the steps of it whose
  // data reached the agent (RobotEstimate::data_held).
  std::set<int> UnionReach(const RobotRun& robot, bool reachable_only) const;
  // The landmarks any robot saw moving within its reach.
  std::set<int> Movers() const;
  // AgreementOfMaps of the robot's map at the end with each peer's whose frame it knows, summed.
  MapAgreement AgreementWithPeers(const RobotRun& robot) const;
  // The robot's summary entry; the union completeness over the robots whose frame it knows.
  nlohmann::json RobotSummaryJson(const std::string& id, const RobotRun& robot) const;
  // The robot's final trajectory (the agent's, else its online path), scored against the truth
  // and written as trajectories/<id>_final.tum: its position RMSE (m) and heading RMSE (deg).
  struct FinalScore {
    double position_rmse_m = 0.0, heading_rmse_deg = 0.0;
  };
  FinalScore ScoreFinalTrajectory(const std::string& id, RobotRun* robot);
  // The robot's rendezvous, each by the transform held at the end of the encounter.
  nlohmann::json ScoreRendezvous(const common::Pose2& frame, const RobotEstimate& last) const;

  common::ScenarioOptions scenario_;
  std::string out_dir_;
  std::ofstream metrics_, tracks_, view_;
  bool started_ = false;
  common::Pose2 frame_g1_;  // tracks are in G1
  std::map<std::string, RobotRun> robots_;
  std::map<std::uint32_t, common::GroundTruth> truth_;  // received, still needed
  std::size_t truth_steps_ = 0;                         // received
  std::uint32_t newest_truth_ = 0;
  std::uint32_t next_view_step_ = 0;    // every step before it is shown
  std::uint32_t next_scored_step_ = 0;  // every step before it is scored
  std::size_t taken_ = 0;
  DeliveryTiming timing_;
};

}  // namespace mrslam::evaluator
