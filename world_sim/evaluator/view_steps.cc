#include "world_sim/evaluator/view_steps.h"

#include <cstdio>
#include <cstdlib>

namespace mrslam::evaluator {

namespace {

using nlohmann::json;

// v with 6 significant digits (a compact file; millimetres on a field of hundreds of metres).
double Round6(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", v);
  return std::strtod(buffer, nullptr);
}

json PoseJson(const common::Pose2& p) { return json::array({Round6(p.x), Round6(p.y), Round6(p.heading)}); }

json TruthJson(const common::GroundTruth& truth) {
  json robots = json::object();
  for (const auto& r : truth.robots) robots[r.id] = PoseJson(r.pose);
  json landmarks = json::array();
  for (const auto& l : truth.landmarks) {
    landmarks.push_back({l.id, Round6(l.pose.x), Round6(l.pose.y), l.moving ? 1 : 0});
  }
  return {{"step", truth.stamp.step}, {"robots", robots}, {"landmarks", landmarks}};
}

json LandmarkJson(const MapLandmark& l) {
  const auto& c = l.covariance_m2;
  return json::array({Round6(l.position_m.x()), Round6(l.position_m.y()), Round6(c(0, 0)), Round6(c(0, 1)),
                      Round6(c(1, 1)), l.moving ? 1 : 0, Round6(l.heading_rad), Round6(l.v_mps), l.landmark_id});
}

json EstimateJson(const RobotEstimate& e) {
  const auto& c = e.covariance;
  json landmarks = json::array();
  for (const auto& l : e.shown_landmarks) landmarks.push_back(LandmarkJson(l));
  json rendezvous = json::array();
  for (const auto& r : e.rendezvous) rendezvous.push_back({r.peer, r.step});
  return {{"step", e.step},
          {"pose", PoseJson(e.pose)},
          {"cov", {Round6(c(0, 0)), Round6(c(0, 1)), Round6(c(1, 1)), Round6(c(2, 2))}},
          {"landmarks", landmarks},
          {"frames_known", e.frames_known},
          {"rendezvous", rendezvous},
          {"rejected", e.rejected_samples},
          {"cpu_ms", Round6(e.step_cpu_ms)}};
}

json ScanJson(const common::LidarScan& scan) {
  json rays = json::array();
  for (const auto& d : scan.landmarks) rays.push_back({Round6(d.range_m), Round6(d.bearing_rad)});
  for (const auto& d : scan.robots) rays.push_back({Round6(d.range_m), Round6(d.bearing_rad)});
  return rays;
}

}  // namespace

json ViewHeader(const common::ScenarioOptions& scenario) {
  json robots = json::array();
  for (const auto& r : scenario.robots) robots.push_back({{"id", r.id}, {"frame", PoseJson(r.frame_in_world)}});
  return {{"scenario", scenario.name},
          {"seed", scenario.seed},
          {"steps", scenario.run.steps},
          {"dt_s", scenario.run.dt_s},
          {"robots", robots}};
}

json ViewStep(const ViewStepInput& input) {
  json step = {{"step", input.step}, {"time_s", Round6(input.time_s)}};
  step["truth"] = input.truth != nullptr ? TruthJson(*input.truth) : json(nullptr);
  step["estimates"] = json::object();
  for (const auto& [id, e] : input.estimates) {
    if (e != nullptr) step["estimates"][id] = EstimateJson(*e);
  }
  if (!input.scans.empty()) {
    step["lidar"] = json::object();
    for (const auto& [id, scan] : input.scans) {
      if (scan != nullptr) step["lidar"][id] = ScanJson(*scan);
    }
  }
  return step;
}

}  // namespace mrslam::evaluator
