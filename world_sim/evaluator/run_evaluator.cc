#include "world_sim/evaluator/run_evaluator.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include <fmt/format.h>
#include <Eigen/Geometry>

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

std::vector<TruePoint> TrueLandmarks(const common::GroundTruth& truth) {
  std::vector<TruePoint> points;
  for (const auto& l : truth.landmarks) points.push_back({l.pose.Translation(), std::stoi(l.id)});
  return points;
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

std::string RunEvaluator::Missing() const {
  const auto last = static_cast<std::uint32_t>(scenario_.run.steps);
  if (truth_.size() < last + 1) return fmt::format("truth: {} of {} steps", truth_.size(), last + 1);
  for (const auto& [id, est] : estimates_) {
    if (est.count(last) == 0) return fmt::format("{}: estimates of {} of {} steps", id, est.size(), last);
    const auto o = odometry_.find(id);
    const std::size_t n = o == odometry_.end() ? 0 : o->second.size();
    if (n < last) return fmt::format("{}: odometry of {} of {} steps", id, n, last);
  }
  return {};
}

nlohmann::json RunEvaluator::Write(const std::string& out_dir, double wall_seconds) const {
  namespace fs = std::filesystem;
  const fs::path out(out_dir);
  fs::create_directories(out / "trajectories");
  if (truth_.empty()) throw std::runtime_error("no ground truth received");
  const auto& truth0 = truth_.begin()->second;
  const Pose2 frame_g1 = FrameOf(truth0, scenario_.robots.front().id);
  const double cutoff_m = 3.0;

  std::ofstream metrics, tracks;
  OpenOrThrow(metrics, out / "metrics.csv");
  OpenOrThrow(tracks, out / "tracks.csv");
  metrics << "step,time_s,robot,x_err_m,y_err_m,position_err_m,heading_err_deg,sigma_x_m,sigma_y_m,"
             "sigma_heading_deg,nees,landmark_rmse_m,landmarks_mapped,map_completeness,ess\n";
  tracks << "step,robot,kind,id,x_m,y_m\n";
  // True landmarks in G1, once per step.
  for (const auto& [step, truth] : truth_) {
    for (const auto& l : truth.landmarks) {
      const auto p = TransformPoint(common::Inverse(frame_g1), l.pose.Translation());
      tracks << fmt::format("{},world,truth_landmark,{},{:.4f},{:.4f}\n", step, l.id, p.x(), p.y());
    }
  }

  nlohmann::json summary;
  summary["scenario"] = scenario_.name;
  summary["seed"] = scenario_.seed;
  summary["steps"] = scenario_.run.steps;
  summary["wall_seconds"] = wall_seconds;
  summary["robots"] = nlohmann::json::object();

  // Whether a landmark is within the lidar's reach of a robot (true poses).
  const auto in_reach = [&](const Pose2& robot_pose, const common::EntityTruth& landmark) {
    const auto z = MeasureRangeBearing(robot_pose, landmark.pose.Translation());
    return z.range_m <= scenario_.sensors.lidar.max_range_m &&
           std::abs(z.bearing_rad) <= scenario_.sensors.lidar.fov_rad / 2.0;
  };
  // Per robot, the true landmarks ever within its reach (for the union completeness).
  std::map<std::string, std::set<int>> reached;
  for (const auto& [step, truth] : truth_) {
    for (const auto& rt : truth.robots) {
      for (const auto& l : truth.landmarks) {
        if (in_reach(rt.pose, l)) reached[rt.id].insert(std::stoi(l.id));
      }
    }
  }

  for (const auto& robot : scenario_.robots) {
    const std::string& id = robot.id;
    const Pose2 frame = FrameOf(truth0, id);
    const Pose2 g1_from_gi = common::Compose(common::Inverse(frame_g1), frame);
    std::ofstream tum_est, tum_truth;
    OpenOrThrow(tum_est, out / "trajectories" / (id + "_estimate.tum"));
    OpenOrThrow(tum_truth, out / "trajectories" / (id + "_truth.tum"));

    std::vector<double> pos_err, head_err, lm_err, dr_err, nees;
    std::set<int> seen;    // true landmark ids ever within the robot's sensor reach
    std::set<int> in_map;  // true landmark ids that stand in the map at the last scored step
    double completeness = 0.0;
    std::size_t mapped = 0;
    // Dead reckoning from the true initial pose in the robot's own frame.
    const auto* r0 = FindEntity(truth0.robots, id);
    Pose2 dead_reckoning = r0 != nullptr ? TruthInOwnFrame(r0->pose, frame) : Pose2{};
    const auto& odo = odometry_.count(id) ? odometry_.at(id) : std::map<std::uint32_t, common::Odometry>{};
    const RobotEstimate* last = nullptr;

    for (const auto& [step, est] : estimates_.at(id)) {
      const auto t_it = truth_.find(step);
      if (t_it == truth_.end()) continue;
      const auto& truth = t_it->second;
      const auto* rt = FindEntity(truth.robots, id);
      if (rt == nullptr) continue;
      const Pose2 truth_own = TruthInOwnFrame(rt->pose, frame);
      const double e_pos = PositionError(est.pose, truth_own);
      const double e_head = HeadingError(est.pose, truth_own);
      const double n = PoseNees(est.pose, est.covariance, truth_own);
      pos_err.push_back(e_pos);
      head_err.push_back(e_head);
      if (std::isfinite(n)) nees.push_back(n);
      if (auto o = odo.find(step); o != odo.end()) {
        for (const auto& g : o->second.segments)
          dead_reckoning = UnicycleStep(dead_reckoning, g.v_mps, g.w_radps, g.dt_s);
        dr_err.push_back(PositionError(dead_reckoning, truth_own));
      }
      // Landmarks the robot could have sensed so far (its true pose, the lidar's reach).
      for (const auto& l : truth.landmarks) {
        if (in_reach(rt->pose, l)) seen.insert(std::stoi(l.id));
      }
      const auto true_points = TrueLandmarks(truth);
      const auto errors = LandmarkErrors(est.landmarks, true_points, frame, cutoff_m);
      lm_err.insert(lm_err.end(), errors.begin(), errors.end());
      const auto matched = MatchedTruth(est.landmarks, true_points, frame, cutoff_m);
      std::size_t matched_seen = 0;
      in_map.clear();
      for (const int j : matched) {
        const int landmark_id = true_points[static_cast<std::size_t>(j)].landmark_id;
        matched_seen += seen.count(landmark_id);
        in_map.insert(landmark_id);
      }
      completeness = seen.empty() ? 1.0 : static_cast<double>(matched_seen) / static_cast<double>(seen.size());
      mapped = est.landmarks.size();

      const Eigen::Vector3d sigma = est.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      metrics << fmt::format(
          "{},{:.3f},{},{:.5f},{:.5f},{:.5f},{:.4f},{:.5f},{:.5f},{:.4f},{:.4f},{:.5f},{},{:.4f},{:.2f}\n", step,
          est.time_s, id, est.pose.x - truth_own.x, est.pose.y - truth_own.y, e_pos,
          common::DegFromRad(common::WrapAngle(est.pose.heading - truth_own.heading)), sigma.x(), sigma.y(),
          common::DegFromRad(sigma.z()), n, Rmse(errors), est.landmarks.size(), completeness,
          est.effective_sample_size);
      tum_est << TumLine(est.time_s, est.pose);
      tum_truth << TumLine(est.time_s, truth_own);
      const Pose2 est_g1 = common::Compose(g1_from_gi, est.pose);
      const Pose2 truth_g1 = common::Compose(g1_from_gi, truth_own);
      tracks << fmt::format("{},{},estimate_robot,{},{:.4f},{:.4f}\n", step, id, id, est_g1.x, est_g1.y);
      tracks << fmt::format("{},{},truth_robot,{},{:.4f},{:.4f}\n", step, id, id, truth_g1.x, truth_g1.y);
      for (std::size_t k = 0; k < est.landmarks.size(); ++k) {
        const auto p = TransformPoint(g1_from_gi, est.landmarks[k].position_m);
        tracks << fmt::format("{},{},estimate_landmark,{},{:.4f},{:.4f}\n", step, id,
                              est.landmarks[k].landmark_id >= 0 ? est.landmarks[k].landmark_id : static_cast<int>(k),
                              p.x(), p.y());
      }
      last = &est;
    }

    nlohmann::json r;
    r["position_rmse_m"] = Rmse(pos_err);
    std::vector<double> head_deg;
    head_deg.reserve(head_err.size());
    for (const double e : head_err) head_deg.push_back(common::DegFromRad(e));
    r["heading_rmse_deg"] = Rmse(head_deg);
    r["landmark_rmse_m"] = Rmse(lm_err);
    r["dead_reckoning_rmse_m"] = Rmse(dr_err);
    double nees_sum = 0.0;
    for (const double v : nees) nees_sum += v;
    r["mean_nees"] = nees.empty() ? 0.0 : nees_sum / static_cast<double>(nees.size());
    r["landmarks_mapped"] = mapped;
    r["map_completeness"] = completeness;
    // Of the landmarks within the reach of this robot or of any robot whose frame it knows (over
    // the whole run), the share in its map at the end.
    std::set<int> union_reach = reached[id];
    if (last != nullptr) {
      for (const auto& peer : last->frames_known) union_reach.insert(reached[peer].begin(), reached[peer].end());
    }
    std::size_t union_mapped = 0;
    for (const int l : union_reach) union_mapped += in_map.count(l);
    r["union_completeness"] =
        union_reach.empty() ? 1.0 : static_cast<double>(union_mapped) / static_cast<double>(union_reach.size());
    r["steps_scored"] = pos_err.size();
    r["frames_known"] = last != nullptr ? last->frames_known : std::vector<std::string>{};
    r["rejected_samples"] = last != nullptr ? last->rejected_samples : 0U;
    // A rendezvous is scored by the transform the robot holds at the end of the encounter:
    // the last report of that peer within 10 steps of the first.
    nlohmann::json rendezvous = nlohmann::json::array();
    if (last != nullptr) {
      std::map<std::string, std::vector<const RendezvousRecord*>> by_peer;
      for (const auto& rec : last->rendezvous) by_peer[rec.peer].push_back(&rec);
      for (const auto& [peer, records] : by_peer) {
        const int j = scenario_.RobotIndex(peer);
        if (j < 0) continue;
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
    }
    r["rendezvous"] = rendezvous;
    summary["robots"][id] = r;
  }
  std::ofstream js;
  OpenOrThrow(js, out / "summary.json");
  js << summary.dump(2) << "\n";
  return summary;
}

}  // namespace mrslam::evaluator
