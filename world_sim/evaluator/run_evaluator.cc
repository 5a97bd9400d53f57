#include "world_sim/evaluator/run_evaluator.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "world_sim/evaluator/view_steps.h"

namespace mrslam::evaluator {

namespace {

using common::Pose2;

const common::EntityTruth* FindEntity(const std::vector<common::EntityTruth>& entities, const std::string& id) {
  for (const auto& e : entities) {
    if (e.id == id) return &e;
  }
  return nullptr;
}

Pose2 FrameOf(const common::GroundTruth& truth, const std::string& robot_id) {
  for (const auto& [id, frame] : truth.frames) {
    if (id == robot_id) return frame;
  }
  throw std::runtime_error("the truth has no frame for robot '" + robot_id + "'");
}

// TUM line: t x y z qx qy qz qw, with the heading as a rotation about z.
std::string TumLine(double t, const Pose2& p) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(p.heading, Eigen::Vector3d::UnitZ()));
  return fmt::format("{:.6f} {:.6f} {:.6f} 0 {:.9f} {:.9f} {:.9f} {:.9f}\n", t, p.x, p.y, q.x(), q.y(), q.z(), q.w());
}

void OpenOrThrow(std::ofstream& out, const std::filesystem::path& path) {
  out.open(path);
  if (!out) throw std::runtime_error("cannot write '" + path.string() + "'");
}

}  // namespace

RunEvaluator::RunEvaluator(const common::ScenarioOptions& scenario) : scenario_(scenario) {
  for (const auto& r : scenario.robots) estimates_[r.id];
}

void RunEvaluator::AddTruth(const common::GroundTruth& truth) { truth_[truth.stamp.step] = truth; }

void RunEvaluator::AddEstimate(const std::string& robot_id, const RobotEstimate& estimate) {
  estimates_[robot_id][estimate.step] = estimate;
}

void RunEvaluator::AddOdometry(const std::string& robot_id, const common::Odometry& odometry) {
  odometry_[robot_id][odometry.stamp.step] = odometry;
}

bool RunEvaluator::Complete() const { return Missing().empty(); }

void RunEvaluator::AddFinalTrajectory(const std::string& robot_id, std::uint32_t chunk, std::vector<FinalPose> poses) {
  final_chunks_[robot_id][chunk] = std::move(poses);
}

double RunEvaluator::ScoreFinalTrajectory(const std::string& id, const Pose2& frame, const std::string& out_dir) const {
  std::vector<FinalPose> path;
  if (const auto f = final_chunks_.find(id); f != final_chunks_.end()) {
    for (const auto& [chunk, poses] : f->second) path.insert(path.end(), poses.begin(), poses.end());
  } else {
    for (const auto& [step, est] : estimates_.at(id)) path.push_back({step, est.time_s, est.pose});
  }
  std::ofstream tum;
  OpenOrThrow(tum, std::filesystem::path(out_dir) / "trajectories" / (id + "_final.tum"));
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& p : path) {
    const auto t = truth_.find(p.step);
    const auto* rt = t == truth_.end() ? nullptr : FindEntity(t->second.robots, id);
    if (rt == nullptr) continue;
    sum += (p.pose.Translation() - TruthInOwnFrame(rt->pose, frame).Translation()).squaredNorm();
    ++n;
    tum << TumLine(p.time_s, p.pose);
  }
  return n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
}

std::string RunEvaluator::Missing() const {
  const auto last = static_cast<std::uint32_t>(scenario_.run.steps);
  if (truth_.size() < last + 1) return fmt::format("truth: {} of {} steps", truth_.size(), last + 1);
  for (const auto& [id, est] : estimates_) {
    if (est.count(last) == 0) return fmt::format("{}: estimates of {} of {} steps", id, est.size(), last);
    const auto o = odometry_.find(id);
    const std::size_t n = o == odometry_.end() ? 0 : o->second.size();
    if (n < last) return fmt::format("{}: odometry of {} of {} steps", id, n, last);
    const std::uint32_t chunks = est.at(last).final_trajectory_chunks;
    const auto f = final_chunks_.find(id);
    const std::size_t got = f == final_chunks_.end() ? 0 : f->second.size();
    if (got < chunks) return fmt::format("{}: final trajectory, {} of {} chunks", id, got, chunks);
  }
  return {};
}

std::size_t RunEvaluator::Held() const {
  std::size_t n = truth_.size();
  for (const auto& [id, steps] : estimates_) n += steps.size();
  for (const auto& [id, steps] : odometry_) n += steps.size();
  for (const auto& [id, chunks] : final_chunks_) n += chunks.size();
  return n;
}

nlohmann::json RunEvaluator::Write(const std::string& out_dir, double wall_seconds) const {
  namespace fs = std::filesystem;
  const fs::path out(out_dir);
  fs::create_directories(out / "trajectories");
  if (truth_.empty()) throw std::runtime_error("no ground truth received");
  const auto& truth0 = truth_.begin()->second;
  Outputs files;
  files.frame_g1 = FrameOf(truth0, scenario_.robots.front().id);
  OpenOrThrow(files.metrics, out / "metrics.csv");
  OpenOrThrow(files.tracks, out / "tracks.csv");
  files.metrics << "step,time_s,robot,x_err_m,y_err_m,position_err_m,heading_err_deg,sigma_x_m,sigma_y_m,"
                   "sigma_heading_deg,nees,landmark_rmse_m,landmarks_mapped,map_completeness,ess\n";
  files.tracks << "step,robot,kind,id,x_m,y_m\n";
  // True landmarks in G1, once per step.
  for (const auto& [step, truth] : truth_) {
    for (const auto& l : truth.landmarks) {
      const auto p = TransformPoint(common::Inverse(files.frame_g1), l.pose.Translation());
      files.tracks << fmt::format("{},world,truth_landmark,{},{:.4f},{:.4f}\n", step, l.id, p.x(), p.y());
    }
  }

  nlohmann::json summary;
  summary["scenario"] = scenario_.name;
  summary["seed"] = scenario_.seed;
  summary["steps"] = scenario_.run.steps;
  summary["wall_seconds"] = wall_seconds;
  summary["robots"] = nlohmann::json::object();
  const auto reached = ReachedLandmarks();
  for (const auto& robot : scenario_.robots) {
    OpenOrThrow(files.tum_estimate, out / "trajectories" / (robot.id + "_estimate.tum"));
    OpenOrThrow(files.tum_truth, out / "trajectories" / (robot.id + "_truth.tum"));
    summary["robots"][robot.id] = ScoreRobot(robot.id, reached, &files);
    summary["robots"][robot.id]["final_trajectory_rmse_m"] =
        ScoreFinalTrajectory(robot.id, FrameOf(truth_.begin()->second, robot.id), out_dir);
    files.tum_estimate.close();
    files.tum_truth.close();
  }
  std::ofstream view;
  OpenOrThrow(view, out / "view.jsonl");
  WriteViewLines(view, ViewHeader(scenario_), truth_, estimates_);
  std::ofstream js;
  OpenOrThrow(js, out / "summary.json");
  js << summary.dump(2) << "\n";
  return summary;
}

std::map<std::string, std::set<int>> RunEvaluator::ReachedLandmarks() const {
  std::map<std::string, std::set<int>> reached;
  for (const auto& [step, truth] : truth_) {
    for (const auto& rt : truth.robots) {
      for (const auto& l : truth.landmarks) {
        if (InLidarReach(scenario_.sensors.lidar, rt.pose, l.pose.Translation()))
          reached[rt.id].insert(std::stoi(l.id));
      }
    }
  }
  return reached;
}

nlohmann::json RunEvaluator::ScoreRobot(const std::string& id, const std::map<std::string, std::set<int>>& reached,
                                        Outputs* files) const {
  const auto& truth0 = truth_.begin()->second;
  const Pose2 frame = FrameOf(truth0, id);
  // Dead reckoning from the true initial pose in the robot's own frame.
  const auto* r0 = FindEntity(truth0.robots, id);
  RobotScorer scorer(frame, r0 != nullptr ? TruthInOwnFrame(r0->pose, frame) : Pose2{}, scenario_.sensors.lidar);
  const auto odometry = odometry_.find(id);
  const RobotEstimate* last = nullptr;
  std::vector<double> step_cpu_ms;
  for (const auto& [step, est] : estimates_.at(id)) {
    step_cpu_ms.push_back(est.step_cpu_ms);
    const auto t_it = truth_.find(step);
    if (t_it == truth_.end()) continue;
    const auto* rt = FindEntity(t_it->second.robots, id);
    if (rt == nullptr) continue;
    const common::Odometry* odo = nullptr;
    if (odometry != odometry_.end()) {
      const auto o = odometry->second.find(step);
      if (o != odometry->second.end()) odo = &o->second;
    }
    const StepScore score = scorer.Add(t_it->second, rt->pose, est.pose, est.covariance, est.landmarks, odo);
    WriteStep(id, common::Compose(common::Inverse(files->frame_g1), frame), est, score, files);
    last = &est;
  }
  const RobotSummary s = scorer.Summary();
  nlohmann::json r;
  r["position_rmse_m"] = s.position_rmse_m;
  r["heading_rmse_deg"] = s.heading_rmse_deg;
  r["landmark_rmse_m"] = s.landmark_rmse_m;
  r["static_landmark_rmse_m"] = s.static_landmark_rmse_m;
  r["moving_landmark_rmse_m"] = s.moving_landmark_rmse_m;
  r["dead_reckoning_rmse_m"] = s.dead_reckoning_rmse_m;
  r["mean_nees"] = s.mean_nees;
  r["landmarks_mapped"] = s.landmarks_mapped;
  r["map_completeness"] = s.map_completeness;
  r["moving_completeness"] = s.moving_completeness;
  // Of the landmarks within the reach of this robot or of any robot whose frame it knows (over
  // the whole run), the share in its map at the end.
  std::set<int> union_reach;
  if (const auto it = reached.find(id); it != reached.end()) union_reach = it->second;
  if (last != nullptr) {
    for (const auto& peer : last->frames_known) {
      if (const auto it = reached.find(peer); it != reached.end())
        union_reach.insert(it->second.begin(), it->second.end());
    }
  }
  std::size_t union_mapped = 0;
  for (const int l : union_reach) union_mapped += scorer.InMap().count(l);
  r["union_completeness"] =
      union_reach.empty() ? 1.0 : static_cast<double>(union_mapped) / static_cast<double>(union_reach.size());
  r["steps_scored"] = s.steps_scored;
  r["step_cpu_ms_median"] = step_cpu_ms.empty() ? 0.0 : Median(step_cpu_ms);
  r["step_cpu_ms_p99"] = step_cpu_ms.empty() ? 0.0 : Percentile(step_cpu_ms, 99.0);
  r["frames_known"] = last != nullptr ? last->frames_known : std::vector<std::string>{};
  r["rejected_samples"] = last != nullptr ? last->rejected_samples : 0U;
  r["rendezvous"] = last != nullptr ? ScoreRendezvous(frame, *last) : nlohmann::json::array();
  return r;
}

void RunEvaluator::WriteStep(const std::string& id, const Pose2& g1_from_gi, const RobotEstimate& est,
                             const StepScore& score, Outputs* files) {
  const Pose2& truth_own = score.truth_own;
  const Eigen::Vector3d sigma = est.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  files->metrics << fmt::format(
      "{},{:.3f},{},{:.5f},{:.5f},{:.5f},{:.4f},{:.5f},{:.5f},{:.4f},{:.4f},{:.5f},{},{:.4f},{:.2f}\n", est.step,
      est.time_s, id, est.pose.x - truth_own.x, est.pose.y - truth_own.y, score.position_err_m,
      common::DegFromRad(common::WrapAngle(est.pose.heading - truth_own.heading)), sigma.x(), sigma.y(),
      common::DegFromRad(sigma.z()), score.nees, Rmse(score.landmark_errors_m), est.landmarks.size(),
      score.map_completeness, est.effective_sample_size);
  files->tum_estimate << TumLine(est.time_s, est.pose);
  files->tum_truth << TumLine(est.time_s, truth_own);
  const Pose2 est_g1 = common::Compose(g1_from_gi, est.pose);
  const Pose2 truth_g1 = common::Compose(g1_from_gi, truth_own);
  files->tracks << fmt::format("{},{},estimate_robot,{},{:.4f},{:.4f}\n", est.step, id, id, est_g1.x, est_g1.y);
  files->tracks << fmt::format("{},{},truth_robot,{},{:.4f},{:.4f}\n", est.step, id, id, truth_g1.x, truth_g1.y);
  for (std::size_t k = 0; k < est.landmarks.size(); ++k) {
    const auto p = TransformPoint(g1_from_gi, est.landmarks[k].position_m);
    files->tracks << fmt::format("{},{},estimate_landmark,{},{:.4f},{:.4f}\n", est.step, id,
                                 est.landmarks[k].landmark_id >= 0 ? est.landmarks[k].landmark_id : static_cast<int>(k),
                                 p.x(), p.y());
  }
}

nlohmann::json RunEvaluator::ScoreRendezvous(const Pose2& frame, const RobotEstimate& last) const {
  // A rendezvous is scored by the transform the robot holds at the end of the encounter:
  // the last report of that peer within 10 steps of the first.
  const auto& truth0 = truth_.begin()->second;
  nlohmann::json rendezvous = nlohmann::json::array();
  std::map<std::string, std::vector<const RendezvousRecord*>> by_peer;
  for (const auto& rec : last.rendezvous) by_peer[rec.peer].push_back(&rec);
  for (const auto& [peer, records] : by_peer) {
    if (scenario_.RobotIndex(peer) < 0) continue;
    const auto first_step = records.front()->step;
    const RendezvousRecord* held = records.front();
    for (const auto* rec : records) {
      if (rec->step <= first_step + 10) held = rec;
    }
    const auto err = FrameTransformError(held->t_self_peer, frame, FrameOf(truth0, peer));
    rendezvous.push_back({{"peer", peer},
                          {"step", first_step},
                          {"transform_error_m", err.translation_m},
                          {"transform_error_deg", common::DegFromRad(err.rotation_rad)}});
  }
  return rendezvous;
}

}  // namespace mrslam::evaluator
