#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "common/config/scenario_options.h"
#include "common/sensor_types.h"
#include "world_sim/evaluator/metrics.h"
#include "world_sim/evaluator/robot_estimate.h"
#include "world_sim/evaluator/robot_scorer.h"

namespace mrslam::evaluator {

// One pose of an agent's final trajectory (its own frame).
struct FinalPose {
  std::uint32_t step = 0;
  double time_s = 0.0;
  common::Pose2 pose;
};

// Scores a run: collects the truth and every robot's estimates and odometry by step, then
// computes the per-step metrics (errors in each robot's own frame, through the true frame
// pose) and the run summary of docs/metrics.md, and writes metrics.csv, summary.json, TUM
// trajectories, tracks.csv (everything in the first robot's frame, for plots) and view.jsonl
// (the run step by step for mrslam_view --run). Pure: no DDS.
class RunEvaluator {
 public:
  explicit RunEvaluator(const common::ScenarioOptions& scenario);

  void AddTruth(const common::GroundTruth& truth);
  void AddEstimate(const std::string& robot_id, const RobotEstimate& estimate);
  void AddOdometry(const std::string& robot_id, const common::Odometry& odometry);
  // A chunk (0..chunks-1) of a robot's final trajectory.
  void AddFinalTrajectory(const std::string& robot_id, std::uint32_t chunk, std::vector<FinalPose> poses);

  // True once the truth of steps 0..N, every robot's estimate of step N and every final
  // trajectory it announced are in.
  bool Complete() const;
  // What is still missing (for a timeout message).
  std::string Missing() const;
  // How many distinct items are held (truth and odometry steps, estimates, final trajectory
  // chunks): it grows only with something new.
  std::size_t Held() const;

  // Computes everything and writes the files into out_dir. Returns the summary.
  nlohmann::json Write(const std::string& out_dir, double wall_seconds) const;

 private:
  // The files Write fills, and the first robot's frame G1 (tracks are in G1).
  struct Outputs {
    std::ofstream metrics, tracks, tum_estimate, tum_truth;
    common::Pose2 frame_g1;
  };
  // Per robot, the true landmarks ever within its reach (for the union completeness).
  std::map<std::string, std::set<int>> ReachedLandmarks() const;
  // Scores robot id step by step (writing its rows, trajectories and tracks); its summary entry.
  nlohmann::json ScoreRobot(const std::string& id, const std::map<std::string, std::set<int>>& reached,
                            Outputs* files) const;
  static void WriteStep(const std::string& id, const common::Pose2& g1_from_gi, const RobotEstimate& estimate,
                        const StepScore& score, Outputs* files);
  // The robot's final trajectory (the agent's, else its online path), scored against the truth
  // and written as trajectories/<id>_final.tum; returns its position RMSE.
  double ScoreFinalTrajectory(const std::string& id, const common::Pose2& frame, const std::string& out_dir) const;
  // The robot's rendezvous, each by the transform held at the end of the encounter.
  nlohmann::json ScoreRendezvous(const common::Pose2& frame, const RobotEstimate& last) const;

  common::ScenarioOptions scenario_;
  std::map<std::uint32_t, common::GroundTruth> truth_;
  std::map<std::string, std::map<std::uint32_t, RobotEstimate>> estimates_;
  std::map<std::string, std::map<std::uint32_t, common::Odometry>> odometry_;
  std::map<std::string, std::map<std::uint32_t, std::vector<FinalPose>>> final_chunks_;
};

}  // namespace mrslam::evaluator
