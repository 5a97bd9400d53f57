#include "world_sim/evaluator/run_evaluator.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
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

std::vector<std::string> RobotIds(const common::ScenarioOptions& scenario) {
  std::vector<std::string> ids;
  for (const auto& r : scenario.robots) ids.push_back(r.id);
  return ids;
}

// Of `expected` samples, how many did not come.
std::size_t Lost(std::size_t received, std::size_t expected) { return expected - std::min(received, expected); }

}  // namespace

RunEvaluator::RunEvaluator(const common::ScenarioOptions& scenario, const std::string& out_dir)
    : scenario_(scenario), out_dir_(out_dir), timing_(RobotIds(scenario)) {
  const std::filesystem::path out(out_dir);
  std::filesystem::create_directories(out / "trajectories");
  OpenOrThrow(metrics_, out / "metrics.csv");
  OpenOrThrow(tracks_, out / "tracks.csv");
  OpenOrThrow(view_, out / "view.jsonl");
  metrics_ << "step,time_s,robot,x_err_m,y_err_m,position_err_m,heading_err_deg,sigma_x_m,sigma_y_m,"
              "sigma_heading_deg,nees,landmark_rmse_m,landmarks_mapped,map_completeness,ess\n";
  tracks_ << "step,robot,kind,id,x_m,y_m\n";
  view_ << ViewHeader(scenario_).dump() << "\n";
  for (const auto& r : scenario.robots) {
    RobotRun& robot = robots_[r.id];
    robot.truth_own.SetLastStep(static_cast<std::uint32_t>(scenario.run.steps));
    OpenOrThrow(robot.tum_estimate, out / "trajectories" / (r.id + "_estimate.tum"));
    OpenOrThrow(robot.tum_truth, out / "trajectories" / (r.id + "_truth.tum"));
    OpenOrThrow(robot.tum_final, out / "trajectories" / (r.id + "_final.tum"));
  }
}

void RunEvaluator::Start(const common::GroundTruth& truth0) {
  frame_g1_ = FrameOf(truth0, scenario_.robots.front().id);
  for (auto& [id, robot] : robots_) {
    robot.frame = FrameOf(truth0, id);
    // Dead reckoning from the true initial pose in the robot's own frame.
    const auto* r0 = FindEntity(truth0.robots, id);
    robot.scorer.emplace(robot.frame, r0 != nullptr ? TruthInOwnFrame(r0->pose, robot.frame) : Pose2{},
                         scenario_.sensors.lidar, scenario_.RobotIndex(id));
  }
  started_ = true;
}

void RunEvaluator::AddTruth(const common::GroundTruth& truth, std::int64_t written_ns) {
  const std::uint32_t step = truth.stamp.step;
  if (truth_steps_ > 0 && step <= newest_truth_ && truth_.count(step) == 0) return;  // a step let go
  if (!started_) Start(truth);
  if (!truth_.emplace(step, truth).second) return;  // sent again
  ++truth_steps_;
  ++taken_;
  newest_truth_ = std::max(newest_truth_, step);
  timing_.StepWritten(step, written_ns);
  for (const auto& rt : truth.robots) {
    const auto robot = robots_.find(rt.id);
    if (robot == robots_.end()) continue;
    robot->second.truth_own.Set(step, TruthInOwnFrame(rt.pose, robot->second.frame));
    for (const auto& l : truth.landmarks) {
      if (InLidarReach(scenario_.sensors.lidar, rt.pose, l.pose.Translation()))
        robot->second.reached.emplace(std::stoi(l.id), step);  // kept when already in
    }
  }
  Advance(false);
}

void RunEvaluator::AddEstimate(const std::string& robot_id, const RobotEstimate& estimate) {
  RobotRun& robot = robots_.at(robot_id);
  if (estimate.step < next_scored_step_ || robot.pending.count(estimate.step) > 0) return;
  robot.pending[estimate.step] = estimate;
  ++taken_;
  ++robot.estimates;
  robot.newest_estimate = std::max(robot.newest_estimate, estimate.step);
  if (estimate.step == static_cast<std::uint32_t>(scenario_.run.steps)) {
    robot.last_step_in = true;
    robot.final_chunks_announced = estimate.final_trajectory_chunks;
  }
  timing_.EstimateDelivered(robot_id, estimate.step,
                            {estimate.written_ns, estimate.received_ns, estimate.step_cpu_ms, estimate.data_hop_us});
  Advance(false);
}

void RunEvaluator::AddOdometry(const std::string& robot_id, const common::Odometry& odometry, std::int64_t written_ns) {
  RobotRun& robot = robots_.at(robot_id);
  const std::uint32_t step = odometry.stamp.step;
  if (step < next_scored_step_ || !robot.odometry.emplace(step, odometry).second) return;
  ++taken_;
  ++robot.odometry_steps;
  robot.newest_odometry = std::max(robot.newest_odometry, step);
  timing_.SensorWritten(robot_id, step, written_ns);
  Advance(false);
}

void RunEvaluator::AddFinalTrajectory(const std::string& robot_id, std::uint32_t chunk, std::vector<FinalPose> poses) {
  if (robots_.at(robot_id).final_chunks.emplace(chunk, std::move(poses)).second) ++taken_;
}

bool RunEvaluator::Complete() const { return Missing().empty(); }

std::string RunEvaluator::Missing() const {
  const auto last = static_cast<std::uint32_t>(scenario_.run.steps);
  // Each stream comes in order (one DDS writer, reliable): once its last step is in, a step not
  // in yet was dropped from the writer's history and will not come.
  if (truth_steps_ == 0 || newest_truth_ < last) return fmt::format("truth: {} of {} steps", truth_steps_, last + 1);
  for (const auto& [id, robot] : robots_) {
    if (!robot.last_step_in) return fmt::format("{}: estimates of {} of {} steps", id, robot.estimates, last);
    if (robot.odometry_steps == 0 || robot.newest_odometry < last) {
      return fmt::format("{}: odometry of {} of {} steps", id, robot.odometry_steps, last);
    }
    if (robot.final_chunks.size() < robot.final_chunks_announced) {
      return fmt::format("{}: final trajectory, {} of {} chunks", id, robot.final_chunks.size(),
                         robot.final_chunks_announced);
    }
  }
  return {};
}

std::size_t RunEvaluator::TruthStepsLost() const {
  return Lost(truth_steps_, static_cast<std::size_t>(scenario_.run.steps) + 1);  // steps 0..N
}

std::size_t RunEvaluator::Pending() const {
  std::size_t n = truth_.size() + timing_.Held();

  for (const auto& [id, robot] : robots_) n += robot.pending.size() + robot.odometry.size();
  return n;
}

void RunEvaluator::Advance(bool finishing) {
  if (!started_) return;
  WriteViewSteps(finishing);
  ScoreSteps(finishing);
  // The truth of a step is needed until the step is shown and scored.
  while (!truth_.empty() && truth_.begin()->first < next_scored_step_) truth_.erase(truth_.begin());
}

std::set<std::uint32_t> RunEvaluator::HeldSteps() const {
  std::set<std::uint32_t> steps;
  for (const auto& [step, truth] : truth_) steps.insert(step);
  for (const auto& [id, robot] : robots_) {
    for (const auto& [step, e] : robot.pending) steps.insert(step);
  }
  return steps;
}

void RunEvaluator::WriteViewSteps(bool finishing) {
  for (const std::uint32_t step : HeldSteps()) {
    if (step < next_view_step_) continue;
    // Live, a step is shown once its truth is in (or a later one) and every robot's estimate
    // of it (or a later one): what is missing then will not come.
    const bool truth_settled = truth_.count(step) > 0 || (truth_steps_ > 0 && newest_truth_ > step);
    bool estimates_settled = true;
    for (const auto& [id, robot] : robots_) {
      estimates_settled =
          estimates_settled && (robot.pending.count(step) > 0 || (robot.estimates > 0 && robot.newest_estimate > step));
    }
    if (!finishing && !(truth_settled && estimates_settled)) break;
    ViewStepInput input;
    input.step = step;
    if (const auto t = truth_.find(step); t != truth_.end()) {
      input.truth = &t->second;
      input.time_s = t->second.stamp.time_s;
    }
    for (const auto& [id, robot] : robots_) {
      if (const auto e = robot.pending.find(step); e != robot.pending.end()) {
        input.estimates[id] = &e->second;
        input.time_s = e->second.time_s;
      }
    }
    view_ << ViewStep(input).dump() << "\n";
    next_view_step_ = step + 1;
  }
}

void RunEvaluator::ScoreSteps(bool finishing) {
  // Step by step, each step's robots in order, so that the files' rows do not depend on the
  // order in which the data arrived. Live, a step waits until it is shown and every robot that has
  // an estimate of it has its odometry (or a later one).
  for (const std::uint32_t step : HeldSteps()) {
    if (!finishing && step >= next_view_step_) return;
    for (const auto& [id, robot] : robots_) {
      const bool awaits_odometry =
          step > 0 && robot.pending.count(step) > 0 && robot.odometry.count(step) == 0 && robot.newest_odometry <= step;
      if (!finishing && awaits_odometry) return;
    }
    if (const auto t = truth_.find(step); t != truth_.end()) {
      for (const auto& l : t->second.landmarks) {
        const auto p = TransformPoint(common::Inverse(frame_g1_), l.pose.Translation());
        tracks_ << fmt::format("{},world,truth_landmark,{},{:.4f},{:.4f}\n", step, l.id, p.x(), p.y());
      }
    }
    for (auto& [id, robot] : robots_) {
      const auto it = robot.pending.find(step);
      if (it == robot.pending.end()) continue;
      const auto o = robot.odometry.find(step);
      ScoreStep(id, &robot, it->second, o == robot.odometry.end() ? nullptr : &o->second);
      robot.odometry.erase(robot.odometry.begin(), robot.odometry.upper_bound(step));
      robot.pending.erase(it);
    }
    next_scored_step_ = step + 1;
  }
}

void RunEvaluator::ScoreStep(const std::string& id, RobotRun* robot, const RobotEstimate& est,
                             const common::Odometry* odo) {
  robot->step_cpu_ms.push_back(est.step_cpu_ms);
  robot->estimator_bytes_final = est.estimator_bytes;
  robot->estimator_bytes_max = std::max(robot->estimator_bytes_max, est.estimator_bytes);
  const auto t_it = truth_.find(est.step);
  if (t_it == truth_.end()) return;
  const auto* rt = FindEntity(t_it->second.robots, id);
  if (rt == nullptr) return;
  const StepScore score = robot->scorer->Add(t_it->second, rt->pose, est.pose, est.covariance, est.landmarks, odo);
  WriteStep(id, est, score, robot);
  robot->online_sum_sq += (est.pose.Translation() - score.truth_own.Translation()).squaredNorm();
  ++robot->online_count;
  robot->tum_final << TumLine(est.time_s, est.pose);
  robot->last = est;
}

nlohmann::json RunEvaluator::Finish(double wall_seconds) {
  if (!started_) throw std::runtime_error("no ground truth received");
  Advance(true);
  nlohmann::json summary;
  summary["scenario"] = scenario_.name;
  summary["seed"] = scenario_.seed;
  summary["steps"] = scenario_.run.steps;
  summary["wall_seconds"] = wall_seconds;
  summary["truth_steps_lost"] = TruthStepsLost();
  summary["robots"] = nlohmann::json::object();
  for (const auto& r : scenario_.robots) {
    RobotRun& robot = robots_.at(r.id);
    summary["robots"][r.id] = RobotSummaryJson(r.id, robot);
    const FinalScore final_score = ScoreFinalTrajectory(r.id, &robot);
    summary["robots"][r.id]["final_trajectory_rmse_m"] = final_score.position_rmse_m;
    summary["robots"][r.id]["final_heading_rmse_deg"] = final_score.heading_rmse_deg;
    robot.tum_estimate.close();
    robot.tum_truth.close();
  }
  metrics_.close();
  tracks_.close();
  view_.close();
  if (!metrics_ || !tracks_ || !view_) throw std::runtime_error("cannot write the run's files in '" + out_dir_ + "'");
  std::ofstream js;
  OpenOrThrow(js, std::filesystem::path(out_dir_) / "summary.json");
  js << summary.dump(2) << "\n";
  return summary;
}

RunEvaluator::FinalScore RunEvaluator::ScoreFinalTrajectory(const std::string& id, RobotRun* robot) {
  if (robot->final_chunks.empty()) {  // the online path, written as it went
    robot->tum_final.close();
    if (robot->online_count == 0) return {};
    return {std::sqrt(robot->online_sum_sq / static_cast<double>(robot->online_count)),
            robot->scorer->Summary().heading_rmse_deg};
  }
  robot->tum_final.close();
  OpenOrThrow(robot->tum_final, std::filesystem::path(out_dir_) / "trajectories" / (id + "_final.tum"));
  double sum = 0.0, heading_sum = 0.0;
  std::size_t n = 0;
  for (const auto& [chunk, poses] : robot->final_chunks) {
    for (const auto& p : poses) {
      const common::Pose2* truth = robot->truth_own.Find(p.step);
      if (truth == nullptr) continue;
      sum += (p.pose.Translation() - truth->Translation()).squaredNorm();
      const double heading_error = common::WrapAngle(p.pose.heading - truth->heading);
      heading_sum += heading_error * heading_error;
      ++n;
      robot->tum_final << TumLine(p.time_s, p.pose);
    }
  }
  robot->tum_final.close();
  if (n == 0) return {};
  return {std::sqrt(sum / static_cast<double>(n)), common::DegFromRad(std::sqrt(heading_sum / static_cast<double>(n)))};
}

nlohmann::json RunEvaluator::RobotSummaryJson(const std::string& id, const RobotRun& robot) const {
  const RobotSummary s = robot.scorer->Summary();
  nlohmann::json r;
  r["position_rmse_m"] = s.position_rmse_m;
  r["heading_rmse_deg"] = s.heading_rmse_deg;
  r["landmark_rmse_m"] = s.landmark_rmse_m;
  r["static_landmark_rmse_m"] = s.static_landmark_rmse_m;
  r["moving_landmark_rmse_m"] = s.moving_landmark_rmse_m;
  r["own_landmark_rmse_m"] = s.own_landmark_rmse_m;
  r["adopted_landmark_nees"] = s.adopted_landmark_nees;
  r["dead_reckoning_rmse_m"] = s.dead_reckoning_rmse_m;
  r["mean_nees"] = s.mean_nees;
  r["landmarks_mapped"] = s.landmarks_mapped;
  r["map_completeness"] = s.map_completeness;
  r["moving_completeness"] = s.moving_completeness;
  // Of the landmarks within the reach of this robot or of the robots whose frames it knows, the
  // share in its map at the end.
  r["union_completeness"] = robot.scorer->Completeness(UnionReach(robot, false));
  std::set<int> reachable = UnionReach(robot, true);
  r["reachable_union_completeness"] = robot.scorer->Completeness(reachable);
  for (const int mover : Movers()) reachable.erase(mover);
  r["static_reachable_union_completeness"] = robot.scorer->Completeness(reachable);
  const MapAgreement agreement = AgreementWithPeers(robot);
  r["common_landmarks"] = agreement.common;
  r["common_landmarks_within_3sd"] =
      agreement.common == 0 ? 1.0 : static_cast<double>(agreement.within) / static_cast<double>(agreement.common);
  r["steps_scored"] = s.steps_scored;
  r["odometry_steps_lost"] = Lost(robot.odometry_steps, static_cast<std::size_t>(scenario_.run.steps));  // 1..N
  r["step_cpu_ms_median"] = robot.step_cpu_ms.empty() ? 0.0 : Median(robot.step_cpu_ms);
  r["step_cpu_ms_p99"] = robot.step_cpu_ms.empty() ? 0.0 : Percentile(robot.step_cpu_ms, 99.0);
  // Per simulated second of the steps the agent went through.
  const double seconds = robot.last ? robot.last->step * scenario_.run.dt_s : 0.0;
  const auto per_s = [&](std::uint64_t bytes) { return seconds > 0.0 ? static_cast<double>(bytes) / seconds : 0.0; };
  r["peer_bytes_sent_per_s"] = robot.last ? per_s(robot.last->peer_bytes_sent) : 0.0;
  r["peer_bytes_received_per_s"] = robot.last ? per_s(robot.last->peer_bytes_received) : 0.0;
  r["estimator_bytes"] = robot.estimator_bytes_max;
  r["estimator_bytes_final"] = robot.estimator_bytes_final;
  const DeliverySummary delivery = timing_.Summary(id);
  r["latency_us_median"] = delivery.latency_us_median;
  r["latency_us_p99"] = delivery.latency_us_p99;
  r["estimate_hop_us_median"] = delivery.estimate_hop_us_median;
  r["data_hop_us_median"] = delivery.data_hop_us_median;
  r["agent_overhead_us_median"] = delivery.agent_overhead_us_median;
  r["late_estimates"] = delivery.late_estimates;
  r["late_estimate_steps"] = delivery.late_steps;
  r["frames_known"] = robot.last ? robot.last->frames_known : std::vector<std::string>{};
  r["data_held"] = robot.last ? robot.last->data_held : std::map<std::string, std::uint32_t>{};
  r["rejected_samples"] = robot.last ? robot.last->rejected_samples : 0U;
  r["peer_messages_late"] = robot.last ? robot.last->peer_messages_late : 0U;
  r["rendezvous"] = robot.last ? ScoreRendezvous(robot.frame, *robot.last) : nlohmann::json::array();
  return r;
}

MapAgreement RunEvaluator::AgreementWithPeers(const RobotRun& robot) const {
  MapAgreement sum;
  if (!robot.last) return sum;
  for (const auto& peer : robot.last->frames_known) {
    const auto it = robots_.find(peer);
    if (it == robots_.end() || !it->second.scorer) continue;
    const MapAgreement a =
        AgreementOfMaps(robot.scorer->InMap(), robot.frame, it->second.scorer->InMap(), it->second.frame);
    sum.common += a.common;
    sum.within += a.within;
  }
  return sum;
}

std::set<int> RunEvaluator::UnionReach(const RobotRun& robot, bool reachable_only) const {
  std::set<int> reach;
  for (const auto& l : robot.reached) reach.insert(l.first);
  if (!robot.last) return reach;
  for (const auto& peer : robot.last->frames_known) {
    const auto it = robots_.find(peer);
    if (it == robots_.end()) continue;
    std::uint32_t until = std::numeric_limits<std::uint32_t>::max();
    if (reachable_only) {
      const auto held = robot.last->data_held.find(peer);
      if (held == robot.last->data_held.end()) continue;  // nothing of it reached the agent
      until = held->second;
    }
    for (const auto& [l, first_step] : it->second.reached) {
      if (first_step <= until) reach.insert(l);
    }
  }
  return reach;
}

std::set<int> RunEvaluator::Movers() const {
  std::set<int> movers;
  for (const auto& [id, robot] : robots_) {
    if (!robot.scorer) continue;
    const std::set<int>& seen = robot.scorer->SeenMoving();
    movers.insert(seen.begin(), seen.end());
  }
  return movers;
}

void RunEvaluator::WriteStep(const std::string& id, const RobotEstimate& est, const StepScore& score, RobotRun* robot) {
  const Pose2 g1_from_gi = common::Compose(common::Inverse(frame_g1_), robot->frame);
  const Pose2& truth_own = score.truth_own;
  const Eigen::Vector3d sigma = est.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  metrics_ << fmt::format(
      "{},{:.3f},{},{:.5f},{:.5f},{:.5f},{:.4f},{:.5f},{:.5f},{:.4f},{:.4f},{:.5f},{},{:.4f},{:.2f}\n", est.step,
      est.time_s, id, est.pose.x - truth_own.x, est.pose.y - truth_own.y, score.position_err_m,
      common::DegFromRad(common::WrapAngle(est.pose.heading - truth_own.heading)), sigma.x(), sigma.y(),
      common::DegFromRad(sigma.z()), score.nees, Rmse(score.landmark_errors_m), est.landmarks.size(),
      score.map_completeness, est.effective_sample_size);
  robot->tum_estimate << TumLine(est.time_s, est.pose);
  robot->tum_truth << TumLine(est.time_s, truth_own);
  const Pose2 est_g1 = common::Compose(g1_from_gi, est.pose);
  const Pose2 truth_g1 = common::Compose(g1_from_gi, truth_own);
  tracks_ << fmt::format("{},{},estimate_robot,{},{:.4f},{:.4f}\n", est.step, id, id, est_g1.x, est_g1.y);
  tracks_ << fmt::format("{},{},truth_robot,{},{:.4f},{:.4f}\n", est.step, id, id, truth_g1.x, truth_g1.y);
  for (std::size_t k = 0; k < est.landmarks.size(); ++k) {
    const auto p = TransformPoint(g1_from_gi, est.landmarks[k].position_m);
    tracks_ << fmt::format("{},{},estimate_landmark,{},{:.4f},{:.4f}\n", est.step, id,
                           est.landmarks[k].landmark_id >= 0 ? est.landmarks[k].landmark_id : static_cast<int>(k),
                           p.x(), p.y());
  }
}

nlohmann::json RunEvaluator::ScoreRendezvous(const Pose2& frame, const RobotEstimate& last) const {
  // A rendezvous is scored by the transform the robot holds at the end of the encounter:
  // the last report of that peer within 10 steps of the first.
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
    const auto err = FrameTransformError(held->t_self_peer, frame, robots_.at(peer).frame);
    rendezvous.push_back({{"peer", peer},
                          {"step", first_step},
                          {"transform_error_m", err.translation_m},
                          {"transform_error_deg", common::DegFromRad(err.rotation_rad)}});
  }
  return rendezvous;
}

}  // namespace mrslam::evaluator
