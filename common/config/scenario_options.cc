#include "common/config/scenario_options.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "common/config/scenario_keys.h"

namespace mrslam::common {
using robot_agent::Association;
using robot_agent::LandmarkKinematics;
using robot_agent::MapFusionRule;
using robot_agent::MotionSource;
using robot_agent::Proposal;

namespace {

// While ScenarioKeys runs: every key path the parser looks up (sequence indices as "[]").
thread_local std::set<std::string>* keys_looked_up = nullptr;

void NoteKeyLookup(const std::string& path) {
  if (keys_looked_up != nullptr) keys_looked_up->insert(std::regex_replace(path, std::regex(R"(\.[0-9]+)"), "[]"));
}

// A YAML mapping being read: remembers which keys were used so that the rest can be reported
// as unknown, and names every key by its full path in errors.
class Section {
 public:
  Section(const YAML::Node& node, std::string path) : node_(node), path_(std::move(path)) {
    if (node_ && !node_.IsNull() && !node_.IsMap()) {
      throw ScenarioError("scenario key '" + PathOr("<root>") + "' must be a mapping");
    }
  }
  ~Section() = default;
  Section(const Section&) = delete;
  Section& operator=(const Section&) = delete;

  bool Has(const std::string& key) {
    used_.insert(key);
    NoteKeyLookup(KeyPath(key));
    return node_ && node_.IsMap() && node_[key] && !node_[key].IsNull();
  }
  std::string KeyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  template <typename T>
  T Get(const std::string& key, const T& fallback) {
    return Has(key) ? Convert<T>(node_[key], KeyPath(key)) : fallback;
  }
  template <typename T>
  T Require(const std::string& key) {
    if (!Has(key)) throw ScenarioError("scenario key '" + KeyPath(key) + "' is missing (required)");
    return Convert<T>(node_[key], KeyPath(key));
  }
  YAML::Node Raw(const std::string& key) {
    used_.insert(key);
    NoteKeyLookup(KeyPath(key));
    return node_ ? node_[key] : YAML::Node();
  }
  Pose2 GetPose(const std::string& key, const Pose2& fallback) {
    if (!Has(key)) return fallback;
    const auto v = Convert<std::vector<double>>(node_[key], KeyPath(key));
    if (v.size() != 3) {
      throw ScenarioError("scenario key '" + KeyPath(key) +
                          "' must be a list of 3 numbers [x_m, y_m, heading_rad], got " + std::to_string(v.size()));
    }
    return {v[0], v[1], WrapAngle(v[2])};
  }
  Eigen::Vector3d GetVector3(const std::string& key, const Eigen::Vector3d& fallback) {
    if (!Has(key)) return fallback;
    const auto v = Convert<std::vector<double>>(node_[key], KeyPath(key));
    if (v.size() != 3) {
      throw ScenarioError("scenario key '" + KeyPath(key) + "' must be a list of 3 numbers");
    }
    return {v[0], v[1], v[2]};
  }
  template <typename E>
  E GetEnum(const std::string& key, E fallback, const std::map<std::string, E>& names) {
    if (!Has(key)) return fallback;
    const auto s = Convert<std::string>(node_[key], KeyPath(key));
    const auto it = names.find(s);
    if (it != names.end()) return it->second;
    std::string allowed;
    for (const auto& [name, value] : names) allowed += (allowed.empty() ? "" : ", ") + name;
    throw ScenarioError("scenario key '" + KeyPath(key) + "' = '" + s + "' is not one of: " + allowed);
  }
  // Throws for the first key of this mapping that was never read.
  void RejectUnknownKeys() const {
    if (!node_ || !node_.IsMap()) return;
    for (const auto& kv : node_) {
      const auto key = kv.first.as<std::string>();
      if (used_.count(key) == 0) {
        throw ScenarioError("scenario key '" + KeyPath(key) + "' is unknown");
      }
    }
  }

  template <typename T>
  static T Convert(const YAML::Node& n, const std::string& path);

 private:
  std::string PathOr(const std::string& fallback) const { return path_.empty() ? fallback : path_; }

  template <typename T>
  static T ConvertImpl(const YAML::Node& n, const std::string& path) {
    try {
      return n.as<T>();
    } catch (const YAML::Exception&) {
      std::ostringstream value;
      value << n;
      throw ScenarioError("scenario key '" + path + "' = '" + value.str() + "' is not " + TypeName<T>());
    }
  }
  template <typename T>
  static std::string TypeName() {
    if constexpr (std::is_same_v<T, bool>)
      return "a boolean";
    else if constexpr (std::is_integral_v<T>)
      return "an integer";
    else if constexpr (std::is_floating_point_v<T>)
      return "a number";
    else if constexpr (std::is_same_v<T, std::string>)
      return "a string";
    else
      return "a list of numbers";
  }

  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
};

template <typename T>
T Section::Convert(const YAML::Node& n, const std::string& path) {
  return ConvertImpl<T>(n, path);
}

YAML::Node RequireSequence(Section& s, const std::string& key) {
  YAML::Node n = s.Raw(key);
  if (!n || n.IsNull()) return YAML::Node(YAML::NodeType::Sequence);
  if (!n.IsSequence()) throw ScenarioError("scenario key '" + s.KeyPath(key) + "' must be a list");
  return n;
}

LandmarkMotionOptions ParseLandmarkMotion(const YAML::Node& node, const std::string& path) {
  Section s(node, path);
  LandmarkMotionOptions m;
  m.model = s.GetEnum<LandmarkMotionModel>("model", LandmarkMotionModel::kStatic,
                                           {{"static", LandmarkMotionModel::kStatic},
                                            {"unicycle", LandmarkMotionModel::kUnicycle},
                                            {"cardinal", LandmarkMotionModel::kCardinal},
                                            {"constant_velocity", LandmarkMotionModel::kConstantVelocity}});
  m.v_mps = s.Get("v_mps", 0.0);
  m.w_radps = s.Get("w_radps", 0.0);
  m.speed_mps = s.Get("speed_mps", 0.0);
  m.reverse_every_steps = s.Get("reverse_every_steps", 20);
  const auto vel = s.Get("velocity_mps", std::vector<double>{0.0, 0.0});
  if (vel.size() != 2) throw ScenarioError("scenario key '" + s.KeyPath("velocity_mps") + "' must be [vx, vy]");
  m.velocity_mps = {vel[0], vel[1]};
  s.RejectUnknownKeys();
  return m;
}

ControlOptions ParseControl(const YAML::Node& node, const std::string& path) {
  Section s(node, path);
  ControlOptions c;
  c.type = s.GetEnum<ControlType>(
      "type", ControlType::kConstant,
      {{"constant", ControlType::kConstant}, {"schedule", ControlType::kSchedule}, {"arc", ControlType::kArc}});
  c.v_mps = s.Get("v_mps", 0.0);
  c.w_radps = s.Get("w_radps", 0.0);
  const YAML::Node segs = RequireSequence(s, "segments");
  for (std::size_t i = 0; i < segs.size(); ++i) {
    Section seg(segs[i], s.KeyPath("segments") + "." + std::to_string(i));
    c.segments.push_back({seg.Get("v_mps", 0.0), seg.Get("w_radps", 0.0), seg.Require<double>("duration_s")});
    seg.RejectUnknownKeys();
  }
  c.radius_m = s.Get("radius_m", 1.0);
  c.speed_mps = s.Get("speed_mps", 0.0);
  c.sweep_rad = s.Get("sweep_rad", 0.0);
  c.turn_left = s.GetEnum<bool>("turn", true, {{"left", true}, {"right", false}});
  s.RejectUnknownKeys();
  return c;
}

std::vector<SlipOptions> ParseSlips(Section& robot) {
  std::vector<SlipOptions> slips;
  const YAML::Node list = RequireSequence(robot, "slips");
  for (std::size_t i = 0; i < list.size(); ++i) {
    Section s(list[i], robot.KeyPath("slips") + "." + std::to_string(i));
    SlipOptions slip;
    slip.step = s.Require<int>("step");
    if (!s.Has("displacement")) {
      throw ScenarioError("scenario key '" + s.KeyPath("displacement") + "' is missing (required)");
    }
    slip.displacement = s.GetPose("displacement", {});
    s.RejectUnknownKeys();
    slips.push_back(slip);
  }
  return slips;
}

// The replay section, if any.
void ParseReplay(Section& top, ScenarioOptions* o) {
  if (!top.Has("replay")) return;
  Section r(top.Raw("replay"), "replay");
  auto& d = o->replay;
  d.enabled = true;
  d.dir = r.Require<std::string>("dir");
  d.step_s = r.Get("step_s", d.step_s);
  d.start_s = r.Get("start_s", d.start_s);
  d.duration_s = r.Require<double>("duration_s");
  if (r.Has("robots")) {
    const YAML::Node list = r.Raw("robots");
    if (!list.IsSequence()) throw ScenarioError("scenario key 'replay.robots' must be a list of robot ids");
    for (std::size_t i = 0; i < list.size(); ++i) {
      d.robots.push_back(Section::Convert<std::string>(list[i], "replay.robots." + std::to_string(i)));
    }
  }
  r.RejectUnknownKeys();
}

// The run section (with a replay, steps and dt_s follow from its window).
void ParseRun(Section& top, ScenarioOptions* o) {
  Section run(top.Raw("run"), "run");
  o->run.mode = run.GetEnum<RunMode>("mode", RunMode::kLockstep,
                                     {{"lockstep", RunMode::kLockstep}, {"realtime", RunMode::kRealtime}});
  o->run.realtime_factor = run.Get("realtime_factor", o->run.realtime_factor);
  o->run.stagger_robots = run.Get("stagger_robots", o->run.stagger_robots);
  if (o->replay.enabled) {
    // Derived from the replay window; a given run.steps may only shorten it, dt_s must agree.
    const double ratio = o->replay.duration_s / o->replay.step_s;
    const int window_steps = o->replay.step_s > 0.0 && std::isfinite(ratio) && ratio < 1e9
                                 ? static_cast<int>(std::lround(ratio))
                                 : 0;  // IsValid names the bad replay key
    o->run.steps = run.Get("steps", window_steps);
    o->run.dt_s = run.Get("dt_s", o->replay.step_s);
    if (o->run.steps > window_steps) {
      throw ScenarioError("scenario key 'run.steps' = " + std::to_string(o->run.steps) +
                          ": must not exceed replay.duration_s / replay.step_s = " + std::to_string(window_steps));
    }
    if (std::abs(o->run.dt_s - o->replay.step_s) > 1e-9) {
      std::ostringstream m;
      m << "scenario key 'run.dt_s' = " << o->run.dt_s << ": must equal replay.step_s = " << o->replay.step_s;
      throw ScenarioError(m.str());
    }
  } else {
    o->run.steps = run.Require<int>("steps");
    o->run.dt_s = run.Require<double>("dt_s");
  }
  o->run.ack_timeout_s = run.Get("ack_timeout_s", o->run.ack_timeout_s);
  o->run.horizon_steps = run.Get("horizon_steps", o->run.horizon_steps);
  o->run.snapshot_every_steps = run.Get("snapshot_every_steps", o->run.snapshot_every_steps);
  o->run.history_steps = run.Get("history_steps", o->run.history_steps);
  o->run.domain = run.Get("domain", o->run.domain);
  run.RejectUnknownKeys();
}

// The listed landmarks.
void ParseLandmarks(Section& top, ScenarioOptions* o) {
  const YAML::Node lms = RequireSequence(top, "landmarks");
  for (std::size_t i = 0; i < lms.size(); ++i) {
    const std::string path = "landmarks." + std::to_string(i);
    Section s(lms[i], path);
    LandmarkOptions l;
    l.id = s.Get("id", static_cast<int>(i) + 1);
    if (!s.Has("pose")) throw ScenarioError("scenario key '" + path + ".pose' is missing (required)");
    l.pose = s.GetPose("pose", {});
    l.motion = ParseLandmarkMotion(s.Raw("motion"), path + ".motion");
    s.RejectUnknownKeys();
    o->landmarks.push_back(l);
  }
}

// The landmark field, if any.
void ParseLandmarkField(Section& top, ScenarioOptions* o) {
  if (!top.Has("landmark_field")) return;
  Section f(top.Raw("landmark_field"), "landmark_field");
  auto& lf = o->landmark_field;
  lf.enabled = true;
  lf.count = f.Require<int>("count");
  const auto area = f.Get("area_m", std::vector<double>{-10, -10, 10, 10});
  if (area.size() != 4)
    throw ScenarioError("scenario key 'landmark_field.area_m' must be [x_min, y_min, x_max, y_max]");
  lf.area_m = {area[0], area[1], area[2], area[3]};
  lf.jitter_m = f.Get("jitter_m", lf.jitter_m);
  lf.moving_fraction = f.Get("moving_fraction", lf.moving_fraction);
  lf.speed_mps = f.Get("speed_mps", lf.speed_mps);
  lf.reverse_every_steps = f.Get("reverse_every_steps", lf.reverse_every_steps);
  lf.first_id = f.Get("first_id", lf.first_id);
  f.RejectUnknownKeys();
}

// The robots.
void ParseRobots(Section& top, ScenarioOptions* o) {
  const YAML::Node robots = RequireSequence(top, "robots");
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const std::string path = "robots." + std::to_string(i);
    Section s(robots[i], path);
    RobotOptions r;
    r.id = s.Require<std::string>("id");
    // A replayed robot's pose defaults to its own frame's origin (its first recorded pose).
    if (!o->replay.enabled && !s.Has("pose")) {
      throw ScenarioError("scenario key '" + path + ".pose' is missing (required)");
    }
    r.initial_pose = s.GetPose("pose", {});
    r.frame_in_world = s.GetPose("frame", r.initial_pose);
    r.control = ParseControl(s.Raw("control"), path + ".control");
    r.slips = ParseSlips(s);
    s.RejectUnknownKeys();
    o->robots.push_back(r);
  }
}

// The sensors: lidar, IMU, odometry.
void ParseSensors(Section& top, ScenarioOptions* o) {
  Section sensors(top.Raw("sensors"), "sensors");
  {
    Section l(sensors.Raw("lidar"), "sensors.lidar");
    auto& d = o->sensors.lidar;
    d.max_range_m = l.Get("max_range_m", d.max_range_m);
    d.min_range_m = l.Get("min_range_m", d.min_range_m);
    d.fov_rad = l.Get("fov_rad", d.fov_rad);
    d.range_noise_sd_m = l.Get("range_noise_sd_m", d.range_noise_sd_m);
    d.bearing_noise_sd_rad = l.Get("bearing_noise_sd_rad", d.bearing_noise_sd_rad);
    d.report_identity = l.Get("report_identity", d.report_identity);
    d.robot_detection_range_m = l.Get("robot_detection_range_m", d.robot_detection_range_m);
    d.detection_probability = l.Get("detection_probability", d.detection_probability);
    l.RejectUnknownKeys();
  }
  {
    Section m(sensors.Raw("imu"), "sensors.imu");
    auto& d = o->sensors.imu;
    d.enabled = m.Get("enabled", d.enabled);
    d.readings_per_step = m.Get("readings_per_step", d.readings_per_step);
    d.gyro_noise_sd_radps = m.Get("gyro_noise_sd_radps", d.gyro_noise_sd_radps);
    d.accel_noise_sd_mps2 = m.Get("accel_noise_sd_mps2", d.accel_noise_sd_mps2);
    m.RejectUnknownKeys();
  }
  {
    Section m(sensors.Raw("odometry"), "sensors.odometry");
    auto& d = o->sensors.odometry;
    d.v_noise_sd_mps = m.Get("v_noise_sd_mps", d.v_noise_sd_mps);
    d.w_noise_sd_radps = m.Get("w_noise_sd_radps", d.w_noise_sd_radps);
    m.RejectUnknownKeys();
  }
  sensors.RejectUnknownKeys();
}

// The process noise.
void ParseNoise(Section& top, ScenarioOptions* o) {
  Section n(top.Raw("noise"), "noise");
  o->noise.robot_process_var = n.GetVector3("robot_process_var", o->noise.robot_process_var);
  o->noise.landmark_process_var = n.GetVector3("landmark_process_var", o->noise.landmark_process_var);
  n.RejectUnknownKeys();
}

// The online smoother's settings (filter.smoother).
void ParseSmoother(Section& filter, robot_agent::SmootherOptions* d) {
  Section s(filter.Raw("smoother"), "filter.smoother");
  d->window_keyframes = s.Get("window_keyframes", d->window_keyframes);
  d->max_keyframe_gap_steps = s.Get("max_keyframe_gap_steps", d->max_keyframe_gap_steps);
  d->relinearize_threshold = s.Get("relinearize_threshold", d->relinearize_threshold);
  d->relinearize_delay_steps = s.Get("relinearize_delay_steps", d->relinearize_delay_steps);
  d->front_end_particles = s.Get("front_end_particles", d->front_end_particles);
  d->max_iterations = s.Get("max_iterations", d->max_iterations);
  d->huber_k = s.Get("huber_k", d->huber_k);
  d->reading_gate_probability = s.Get("reading_gate_probability", d->reading_gate_probability);
  d->speed_factor_sd = s.Get("speed_factor_sd", d->speed_factor_sd);
  d->turn_factor_sd = s.Get("turn_factor_sd", d->turn_factor_sd);
  d->turn_bias_sd_radps = s.Get("turn_bias_sd_radps", d->turn_bias_sd_radps);
  d->lost_after_keyframes = s.Get("lost_after_keyframes", d->lost_after_keyframes);
  d->min_recovery_readings = s.Get("min_recovery_readings", d->min_recovery_readings);
  d->max_relocation_m = s.Get("max_relocation_m", d->max_relocation_m);
  d->mover_memory_s = s.Get("mover_memory_s", d->mover_memory_s);
  s.RejectUnknownKeys();
}

// The filter.
void ParseFilter(Section& top, ScenarioOptions* o) {
  Section f(top.Raw("filter"), "filter");
  auto& d = o->filter;
  d.type = f.Get("type", d.type);
  d.particles = f.Get("particles", d.particles);
  d.motion_source = f.GetEnum<MotionSource>("motion_source", d.motion_source,
                                            {{"odometry", MotionSource::kOdometry}, {"imu", MotionSource::kImu}});
  d.proposal = f.GetEnum<Proposal>("proposal", d.proposal,
                                   {{"motion", Proposal::kMotion}, {"measurement", Proposal::kMeasurement}});
  d.association =
      f.GetEnum<Association>("association", d.association,
                             {{"mahalanobis", Association::kMahalanobis}, {"euclidean", Association::kEuclidean}});
  d.gate_probability = f.Get("gate_probability", d.gate_probability);
  d.new_landmark_probability = f.Get("new_landmark_probability", d.new_landmark_probability);
  d.euclidean_gate = f.Get("euclidean_gate", d.euclidean_gate);
  d.landmark_kinematics =
      f.GetEnum<LandmarkKinematics>("landmark_kinematics", d.landmark_kinematics,
                                    {{"static", LandmarkKinematics::kStatic},
                                     {"known_candidates", LandmarkKinematics::kKnownCandidates},
                                     {"constant_turn_rate", LandmarkKinematics::kConstantTurnRate}});
  const YAML::Node kk = RequireSequence(f, "known_kinematics");
  for (std::size_t i = 0; i < kk.size(); ++i) {
    Section k(kk[i], "filter.known_kinematics." + std::to_string(i));
    d.known_kinematics.push_back({k.Require<double>("v_mps"), k.Require<double>("w_radps")});
    k.RejectUnknownKeys();
  }
  d.max_landmark_speed_mps = f.Get("max_landmark_speed_mps", d.max_landmark_speed_mps);
  d.landmark_speed_process_var = f.Get("landmark_speed_process_var", d.landmark_speed_process_var);
  d.landmark_turn_rate_process_var = f.Get("landmark_turn_rate_process_var", d.landmark_turn_rate_process_var);
  d.landmark_turn_rate_prior_sd_radps = f.Get("landmark_turn_rate_prior_sd_radps", d.landmark_turn_rate_prior_sd_radps);
  d.landmark_static_prior = f.Get("landmark_static_prior", d.landmark_static_prior);
  d.confirm_sightings = f.Get("confirm_sightings", d.confirm_sightings);
  d.drop_after_misses = f.Get("drop_after_misses", d.drop_after_misses);
  d.max_landmark_position_sd_m = f.Get("max_landmark_position_sd_m", d.max_landmark_position_sd_m);
  d.ela_gate_probability = f.Get("ela_gate_probability", d.ela_gate_probability);
  d.ela_return_after_frames = f.Get("ela_return_after_frames", d.ela_return_after_frames);
  d.ela_drift_window_frames = f.Get("ela_drift_window_frames", d.ela_drift_window_frames);
  d.ela_outside_frames_to_move = f.Get("ela_outside_frames_to_move", d.ela_outside_frames_to_move);
  d.ela_drop_unseen_after_frames = f.Get("ela_drop_unseen_after_frames", d.ela_drop_unseen_after_frames);
  d.ela_young_sightings = f.Get("ela_young_sightings", d.ela_young_sightings);
  d.ela_young_creep_share = f.Get("ela_young_creep_share", d.ela_young_creep_share);
  d.resample_ess_fraction = f.Get("resample_ess_fraction", d.resample_ess_fraction);
  d.resample_every_step = f.Get("resample_every_step", d.resample_every_step);
  d.odometry_scale = f.Get("odometry_scale", d.odometry_scale);
  d.odometry_turn_scale = f.Get("odometry_turn_scale", d.odometry_turn_scale);
  d.odometry_lag_s = f.Get("odometry_lag_s", d.odometry_lag_s);
  d.outlier_gate_probability = f.Get("outlier_gate_probability", d.outlier_gate_probability);
  ParseSmoother(f, &d.smoother);
  f.RejectUnknownKeys();
}

// The rendezvous detector.
void ParseRendezvous(Section& top, ScenarioOptions* o) {
  Section r(top.Raw("rendezvous"), "rendezvous");
  auto& d = o->rendezvous;
  d.enable_from_step = r.Get("enable_from_step", d.enable_from_step);
  d.window_steps = r.Get("window_steps", d.window_steps);
  d.min_interval_steps = r.Get("min_interval_steps", d.min_interval_steps);
  r.RejectUnknownKeys();
}

// Cooperation among the agents.
void ParseCooperation(Section& top, ScenarioOptions* o) {
  Section c(top.Raw("cooperation"), "cooperation");
  auto& d = o->cooperation;
  d.map_fusion = c.GetEnum<MapFusionRule>("map_fusion", d.map_fusion,
                                          {{"covariance_intersection", MapFusionRule::kCovarianceIntersection},
                                           {"weighted", MapFusionRule::kWeighted},
                                           {"average", MapFusionRule::kAverage}});
  d.merge_maps = c.Get("merge_maps", d.merge_maps);
  d.max_snapshot_landmarks = c.Get("max_snapshot_landmarks", d.max_snapshot_landmarks);
  d.min_seen_span_steps = c.Get("min_seen_span_steps", d.min_seen_span_steps);
  d.cooperative_localization = c.Get("cooperative_localization", d.cooperative_localization);
  d.match_gate_probability = c.Get("match_gate_probability", d.match_gate_probability);
  d.merge_min_separation_m = c.Get("merge_min_separation_m", d.merge_min_separation_m);
  d.transform_gate_probability = c.Get("transform_gate_probability", d.transform_gate_probability);
  d.joint_transform = c.Get("joint_transform", d.joint_transform);
  d.max_history_steps = c.Get("max_history_steps", d.max_history_steps);
  d.share_factors = c.Get("share_factors", d.share_factors);
  d.exchange_window_steps = c.Get("exchange_window_steps", d.exchange_window_steps);
  d.max_batch_steps = c.Get("max_batch_steps", d.max_batch_steps);
  d.relay_factors = c.Get("relay_factors", d.relay_factors);
  d.stream_landmarks = c.Get("stream_landmarks", d.stream_landmarks);
  d.joint_every_s = c.Get("joint_every_s", d.joint_every_s);
  c.RejectUnknownKeys();
}

// A replay of a subset keeps only those robots (in scenario order).
void KeepReplayedRobots(ScenarioOptions* o) {
  if (o->replay.robots.empty()) return;
  for (std::size_t i = 0; i < o->replay.robots.size(); ++i) {
    const auto& id = o->replay.robots[i];
    if (o->RobotIndex(id) < 0) {
      throw ScenarioError("scenario key 'replay.robots." + std::to_string(i) + "' = '" + id +
                          "' is not one of the scenario's robots");
    }
  }
  std::vector<RobotOptions> kept;
  for (const auto& r : o->robots) {
    if (std::find(o->replay.robots.begin(), o->replay.robots.end(), r.id) != o->replay.robots.end()) {
      kept.push_back(r);
    }
  }
  o->robots = kept;
}

}  // namespace

int ScenarioOptions::RobotIndex(const std::string& id) const {
  for (std::size_t i = 0; i < robots.size(); ++i) {
    if (robots[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

ScenarioOptions CreateScenarioOptions(const YAML::Node& root) {
  if (!root || !root.IsMap()) throw ScenarioError("scenario must be a YAML mapping at the top level");
  Section top(root, "");
  ScenarioOptions o;
  o.name = top.Require<std::string>("name");
  o.seed = top.Get<std::uint64_t>("seed", 1);
  ParseReplay(top, &o);
  ParseRun(top, &o);
  ParseLandmarks(top, &o);
  ParseLandmarkField(top, &o);
  ParseRobots(top, &o);
  ParseSensors(top, &o);
  ParseNoise(top, &o);
  ParseFilter(top, &o);
  ParseRendezvous(top, &o);
  ParseCooperation(top, &o);
  top.RejectUnknownKeys();
  KeepReplayedRobots(&o);
  return o;
}

namespace {

// Collects the first violated rule as "scenario key 'k' = v: rule".
class Checker {
 public:
  explicit Checker(std::string* error) : error_(error) {}
  template <typename T>
  bool Check(bool ok, const std::string& key, const T& value, const std::string& rule) {
    if (!ok && failed_ == false) {
      failed_ = true;
      std::ostringstream s;
      s << "scenario key '" << key << "' = " << value << ": " << rule;
      if (error_ != nullptr) *error_ = s.str();
    }
    return ok;
  }
  bool ok() const { return !failed_; }

 private:
  std::string* error_;
  bool failed_ = false;
};

// Bounds on sizes, checked before anything is allocated or looped over by them.
constexpr std::size_t kMaxRobots = 64;
constexpr std::size_t kMaxLandmarks = 100000;
constexpr int kMaxSteps = 10000000;
constexpr std::size_t kMaxNameBytes = 128;
constexpr std::size_t kMaxRobotIdBytes = 32;

// True for well-formed UTF-8 (no overlong forms, surrogates or code points past U+10FFFF) without
// control characters.
bool ValidUtf8(const std::string& text) {
  const auto* s = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned char b = s[i];
    if (b < 0x80) {
      if (b < 0x20 || b == 0x7f) return false;
      ++i;
      continue;
    }
    const std::size_t extra = b >= 0xf0 ? 3 : b >= 0xe0 ? 2 : b >= 0xc0 ? 1 : 0;
    if (extra == 0 || b > 0xf4 || i + extra >= n) return false;
    std::uint32_t cp = b & (0x3fU >> extra);
    for (std::size_t k = 1; k <= extra; ++k) {
      if ((s[i + k] & 0xc0) != 0x80) return false;
      cp = (cp << 6) | (s[i + k] & 0x3fU);
    }
    constexpr std::uint32_t kMinOfLength[] = {0, 0x80, 0x800, 0x10000};
    const bool overlong = cp < kMinOfLength[extra];
    const bool surrogate = cp >= 0xd800 && cp <= 0xdfff;
    const bool c1_control = cp >= 0x80 && cp < 0xa0;
    if (overlong || surrogate || c1_control || cp > 0x10ffff) return false;
    i += extra + 1;
  }
  return true;
}

bool Finite(const Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.heading); }
std::string PoseText(const Pose2& p) {
  std::ostringstream s;
  s << "[" << p.x << ", " << p.y << ", " << p.heading << "]";
  return s.str();
}

}  // namespace

namespace {

// The name, the replay and the run.
void CheckRun(const ScenarioOptions& o, Checker* c) {
  const auto& name = o.name;
  const auto& replay = o.replay;
  const auto& run = o.run;
  const auto& robots = o.robots;
  c->Check(!name.empty(), "name", "''", "must not be empty");
  c->Check(name.size() <= kMaxNameBytes && ValidUtf8(name), "name", "(not shown)",
           "must be valid UTF-8 of at most 128 bytes without control characters");
  if (replay.enabled) {
    c->Check(!replay.dir.empty(), "replay.dir", "''", "must not be empty");
    c->Check(replay.step_s > 0.0 && std::isfinite(replay.step_s), "replay.step_s", replay.step_s, "must be positive");
    c->Check(replay.start_s >= 0.0 && std::isfinite(replay.start_s), "replay.start_s", replay.start_s,
             "must not be negative");
    c->Check(replay.duration_s >= replay.step_s && std::isfinite(replay.duration_s), "replay.duration_s",
             replay.duration_s, "must be at least replay.step_s");
    for (std::size_t i = 0; i < robots.size(); ++i) {
      const auto& id = robots[i].id;
      const bool subject = id.size() >= 2 && id[0] == 'r' && id[1] != '0' &&
                           id.find_first_not_of("0123456789", 1) == std::string::npos && id.size() <= 4;
      c->Check(subject, "robots." + std::to_string(i) + ".id", id,
               "a replayed robot must be named r<n> (MRCLAM subject n)");
    }
  }
  c->Check(run.steps >= 1 && run.steps <= kMaxSteps, "run.steps", run.steps, "must be in 1..10000000");
  c->Check(run.dt_s > 0.0 && std::isfinite(run.dt_s), "run.dt_s", run.dt_s, "must be positive");
  c->Check(run.realtime_factor > 0.0, "run.realtime_factor", run.realtime_factor, "must be positive");
  c->Check(run.ack_timeout_s > 0.0, "run.ack_timeout_s", run.ack_timeout_s, "must be positive");
  c->Check(run.horizon_steps >= 1 && run.horizon_steps <= 1000000, "run.horizon_steps", run.horizon_steps,
           "must be in 1..1000000");
  c->Check(run.snapshot_every_steps >= 1 && run.snapshot_every_steps <= 100000, "run.snapshot_every_steps",
           run.snapshot_every_steps, "must be in 1..100000");
  c->Check(run.history_steps > run.snapshot_every_steps && run.history_steps <= 1000000, "run.history_steps",
           run.history_steps,
           "must exceed run.snapshot_every_steps (a restarted agent takes the steps since its snapshot from the "
           "history) and be at most 1000000");
  c->Check(run.domain >= 0 && run.domain <= 232, "run.domain", run.domain, "must be in 0..232");
  c->Check(!robots.empty(), "robots", "[]", "at least one robot is required");
  c->Check(robots.size() <= kMaxRobots, "robots", robots.size(), "at most 64 robots (one process each)");
}

// The robots: ids, poses, controls, slips.
void CheckRobots(const ScenarioOptions& o, Checker* c) {
  const auto& replay = o.replay;
  const auto& robots = o.robots;
  std::set<std::string> robot_ids;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const auto& r = robots[i];
    const std::string p = "robots." + std::to_string(i);
    c->Check(!r.id.empty(), p + ".id", "''", "must not be empty");
    c->Check(r.id.size() <= kMaxRobotIdBytes &&
                 r.id.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") ==
                     std::string::npos,
             p + ".id", r.id.size() <= kMaxRobotIdBytes && ValidUtf8(r.id) ? r.id : "(not shown)",
             "at most 32 letters, digits, '_' or '-' (it names DDS topics)");
    c->Check(r.id != "world", p + ".id", r.id, "'world' is reserved");
    c->Check(robot_ids.insert(r.id).second, p + ".id", r.id, "duplicate robot id");
    c->Check(Finite(r.initial_pose), p + ".pose", PoseText(r.initial_pose), "must be finite");
    c->Check(Finite(r.frame_in_world), p + ".frame", PoseText(r.frame_in_world), "must be finite");
    const auto& ct = r.control;
    c->Check(std::isfinite(ct.v_mps) && std::isfinite(ct.w_radps), p + ".control", ct.v_mps,
             "v_mps and w_radps must be finite");
    for (std::size_t k = 0; k < ct.segments.size(); ++k) {
      c->Check(ct.segments[k].duration_s > 0.0, p + ".control.segments." + std::to_string(k) + ".duration_s",
               ct.segments[k].duration_s, "must be positive");
    }
    if (ct.type == ControlType::kSchedule) {
      c->Check(!ct.segments.empty(), p + ".control.segments", "[]", "a schedule needs at least one segment");
    }
    if (ct.type == ControlType::kArc) {
      c->Check(ct.radius_m > 0.0, p + ".control.radius_m", ct.radius_m, "must be positive");
      c->Check(ct.sweep_rad >= 0.0, p + ".control.sweep_rad", ct.sweep_rad, "must not be negative");
    }
    c->Check(!replay.enabled || r.slips.empty(), p + ".slips", r.slips.size(), "a replayed robot cannot slip");
    for (std::size_t k = 0; k < r.slips.size(); ++k) {
      const std::string slip = p + ".slips." + std::to_string(k);
      c->Check(r.slips[k].step >= 1, slip + ".step", r.slips[k].step, "must be at least 1");
      c->Check(Finite(r.slips[k].displacement), slip + ".displacement", PoseText(r.slips[k].displacement),
               "must be finite");
    }
  }
}

// The listed landmarks and the landmark field.
void CheckLandmarks(const ScenarioOptions& o, Checker* c) {
  const auto& landmarks = o.landmarks;
  const auto& landmark_field = o.landmark_field;
  std::set<int> landmark_ids;
  if (!c->Check(landmarks.size() <= kMaxLandmarks, "landmarks", landmarks.size(), "at most 100000 landmarks")) return;
  for (std::size_t i = 0; i < landmarks.size(); ++i) {
    const auto& l = landmarks[i];
    const std::string p = "landmarks." + std::to_string(i);
    c->Check(l.id >= 0, p + ".id", l.id, "must not be negative");
    c->Check(landmark_ids.insert(l.id).second, p + ".id", l.id, "duplicate landmark id");
    c->Check(Finite(l.pose), p + ".pose", PoseText(l.pose), "must be finite");
    if (l.motion.model == LandmarkMotionModel::kCardinal) {
      c->Check(l.motion.reverse_every_steps >= 1, p + ".motion.reverse_every_steps", l.motion.reverse_every_steps,
               "must be at least 1");
      c->Check(l.motion.speed_mps >= 0.0, p + ".motion.speed_mps", l.motion.speed_mps, "must not be negative");
    }
  }
  if (landmark_field.enabled) {
    const auto& f = landmark_field;
    if (!c->Check(f.count >= 1 && static_cast<std::size_t>(f.count) <= kMaxLandmarks, "landmark_field.count", f.count,
                  "must be in 1..100000"))
      return;
    c->Check(f.area_m[2] > f.area_m[0] && f.area_m[3] > f.area_m[1], "landmark_field.area_m", f.area_m.transpose(),
             "x_max > x_min and y_max > y_min");
    c->Check(f.jitter_m >= 0.0, "landmark_field.jitter_m", f.jitter_m, "must not be negative");
    c->Check(f.moving_fraction >= 0.0 && f.moving_fraction <= 1.0, "landmark_field.moving_fraction", f.moving_fraction,
             "must be in [0, 1]");
    c->Check(f.speed_mps >= 0.0, "landmark_field.speed_mps", f.speed_mps, "must not be negative");
    c->Check(f.reverse_every_steps >= 1, "landmark_field.reverse_every_steps", f.reverse_every_steps,
             "must be at least 1");
    const auto first_listed_at_or_after = landmark_ids.lower_bound(f.first_id);
    c->Check(f.first_id >= 0 && f.first_id <= std::numeric_limits<int>::max() - f.count, "landmark_field.first_id",
             f.first_id, "must be in 0..2147483647 - count");
    c->Check(first_listed_at_or_after == landmark_ids.end() ||
                 static_cast<long long>(*first_listed_at_or_after) >= static_cast<long long>(f.first_id) + f.count,
             "landmark_field.first_id", f.first_id, "generated ids collide with the ids of 'landmarks'");
  }
}

// The sensors and the process noise.
void CheckSensors(const ScenarioOptions& o, Checker* c) {
  const auto& sensors = o.sensors;
  const auto& noise = o.noise;
  const auto& l = sensors.lidar;
  c->Check(l.max_range_m > 0.0, "sensors.lidar.max_range_m", l.max_range_m, "must be positive");
  c->Check(l.min_range_m >= 0.0 && l.min_range_m < l.max_range_m, "sensors.lidar.min_range_m", l.min_range_m,
           "must be in [0, max_range_m)");
  c->Check(l.fov_rad > 0.0 && l.fov_rad <= 2.0 * kPi + 1e-9, "sensors.lidar.fov_rad", l.fov_rad,
           "must be in (0, 2*pi]");
  c->Check(l.range_noise_sd_m >= 0.0, "sensors.lidar.range_noise_sd_m", l.range_noise_sd_m, "must not be negative");
  c->Check(l.bearing_noise_sd_rad >= 0.0, "sensors.lidar.bearing_noise_sd_rad", l.bearing_noise_sd_rad,
           "must not be negative");
  c->Check(l.robot_detection_range_m >= 0.0, "sensors.lidar.robot_detection_range_m", l.robot_detection_range_m,
           "must not be negative");
  c->Check(l.detection_probability > 0.0 && l.detection_probability <= 1.0, "sensors.lidar.detection_probability",
           l.detection_probability, "must be in (0, 1]");
  const auto& m = sensors.imu;
  c->Check(m.readings_per_step >= 1, "sensors.imu.readings_per_step", m.readings_per_step, "must be at least 1");
  c->Check(m.gyro_noise_sd_radps >= 0.0, "sensors.imu.gyro_noise_sd_radps", m.gyro_noise_sd_radps,
           "must not be negative");
  c->Check(m.accel_noise_sd_mps2 >= 0.0, "sensors.imu.accel_noise_sd_mps2", m.accel_noise_sd_mps2,
           "must not be negative");
  c->Check(sensors.odometry.v_noise_sd_mps >= 0.0, "sensors.odometry.v_noise_sd_mps", sensors.odometry.v_noise_sd_mps,
           "must not be negative");
  c->Check(sensors.odometry.w_noise_sd_radps >= 0.0, "sensors.odometry.w_noise_sd_radps",
           sensors.odometry.w_noise_sd_radps, "must not be negative");
  c->Check((noise.robot_process_var.array() >= 0.0).all(), "noise.robot_process_var",
           noise.robot_process_var.transpose(), "variances must not be negative");
  c->Check((noise.landmark_process_var.array() >= 0.0).all(), "noise.landmark_process_var",
           noise.landmark_process_var.transpose(), "variances must not be negative");
}

// The online smoother's settings.
void CheckSmoother(const robot_agent::SmootherOptions& s, Checker* c) {
  c->Check(s.window_keyframes >= 2 && s.window_keyframes <= 10000, "filter.smoother.window_keyframes",
           s.window_keyframes, "must be in 2..10000");
  c->Check(s.max_keyframe_gap_steps >= 1 && s.max_keyframe_gap_steps <= 10000, "filter.smoother.max_keyframe_gap_steps",
           s.max_keyframe_gap_steps, "must be in 1..10000");
  c->Check(s.relinearize_threshold >= 0.0 && s.relinearize_threshold <= 100.0, "filter.smoother.relinearize_threshold",
           s.relinearize_threshold, "must be in [0, 100]");
  c->Check(s.relinearize_delay_steps >= 0 && s.relinearize_delay_steps < s.window_keyframes,
           "filter.smoother.relinearize_delay_steps", s.relinearize_delay_steps,
           "must be in [0, filter.smoother.window_keyframes)");
  c->Check(s.front_end_particles >= 1 && s.front_end_particles <= 100000, "filter.smoother.front_end_particles",
           s.front_end_particles, "must be in 1..100000");
  c->Check(s.max_iterations >= 1 && s.max_iterations <= 1000, "filter.smoother.max_iterations", s.max_iterations,
           "must be in 1..1000");
  c->Check(s.huber_k > 0.0 && std::isfinite(s.huber_k), "filter.smoother.huber_k", s.huber_k, "must be positive");
  c->Check(s.reading_gate_probability > 0.0 && s.reading_gate_probability < 1.0,
           "filter.smoother.reading_gate_probability", s.reading_gate_probability, "must be in (0, 1)");
  for (const auto& [key, sd] : {std::pair{"speed_factor_sd", s.speed_factor_sd},
                                {"turn_factor_sd", s.turn_factor_sd},
                                {"turn_bias_sd_radps", s.turn_bias_sd_radps}}) {
    c->Check(sd > 0.0 && std::isfinite(sd), std::string("filter.smoother.") + key, sd, "must be positive");
  }
  c->Check(s.lost_after_keyframes >= 1, "filter.smoother.lost_after_keyframes", s.lost_after_keyframes,
           "must be at least 1");
  c->Check(s.min_recovery_readings >= 2, "filter.smoother.min_recovery_readings", s.min_recovery_readings,
           "must be at least 2");
  c->Check(s.max_relocation_m > 0.0 && std::isfinite(s.max_relocation_m), "filter.smoother.max_relocation_m",
           s.max_relocation_m, "must be positive");
  c->Check(s.mover_memory_s >= 0.0 && std::isfinite(s.mover_memory_s), "filter.smoother.mover_memory_s",
           s.mover_memory_s, "must be finite and not negative");
}

// The filter.
void CheckFilter(const ScenarioOptions& o, Checker* c) {
  const auto& sensors = o.sensors;
  const auto& filter = o.filter;
  const auto& f = filter;
  c->Check(f.type == "fastslam" || f.type == "ekf" || f.type == "ekf_ela" || f.type == "smoother", "filter.type",
           f.type, "must be one of fastslam, ekf, ekf_ela, smoother");
  c->Check(f.particles >= 1 && f.particles <= 1000000, "filter.particles", f.particles, "must be in 1..1000000");
  CheckSmoother(f.smoother, c);
  if (f.motion_source == MotionSource::kImu) {
    c->Check(f.type == "fastslam", "filter.motion_source", "imu", "is supported by the fastslam filter only");
    c->Check(sensors.imu.enabled, "filter.motion_source", "imu", "needs sensors.imu.enabled");
  }
  c->Check(f.gate_probability > 0.0 && f.gate_probability < 1.0, "filter.gate_probability", f.gate_probability,
           "must be in (0, 1)");
  c->Check(f.new_landmark_probability >= f.gate_probability && f.new_landmark_probability < 1.0,
           "filter.new_landmark_probability", f.new_landmark_probability, "must be in [gate_probability, 1)");
  c->Check(f.euclidean_gate > 0.0, "filter.euclidean_gate", f.euclidean_gate, "must be positive");
  c->Check(f.landmark_kinematics != LandmarkKinematics::kKnownCandidates || !f.known_kinematics.empty(),
           "filter.known_kinematics", "[]", "needed when landmark_kinematics is known_candidates");
  c->Check(f.max_landmark_speed_mps >= 0.0, "filter.max_landmark_speed_mps", f.max_landmark_speed_mps,
           "must not be negative");
  c->Check(f.landmark_speed_process_var >= 0.0, "filter.landmark_speed_process_var", f.landmark_speed_process_var,
           "must not be negative");
  c->Check(f.landmark_turn_rate_process_var >= 0.0, "filter.landmark_turn_rate_process_var",
           f.landmark_turn_rate_process_var, "must not be negative");
  c->Check(f.landmark_turn_rate_prior_sd_radps > 0.0, "filter.landmark_turn_rate_prior_sd_radps",
           f.landmark_turn_rate_prior_sd_radps, "must be positive");
  c->Check(f.landmark_static_prior >= 0.0 && f.landmark_static_prior < 1.0, "filter.landmark_static_prior",
           f.landmark_static_prior, "must be in [0, 1)");
  c->Check(f.confirm_sightings >= 1, "filter.confirm_sightings", f.confirm_sightings, "must be at least 1");
  c->Check(f.drop_after_misses >= 1, "filter.drop_after_misses", f.drop_after_misses, "must be at least 1");
  c->Check(f.max_landmark_position_sd_m > 0.0, "filter.max_landmark_position_sd_m", f.max_landmark_position_sd_m,
           "must be positive (.inf: no bound)");
  c->Check(f.ela_gate_probability > 0.0 && f.ela_gate_probability < 1.0, "filter.ela_gate_probability",
           f.ela_gate_probability, "must be in (0, 1)");
  c->Check(f.ela_return_after_frames >= 1, "filter.ela_return_after_frames", f.ela_return_after_frames,
           "must be at least 1");
  c->Check(f.ela_drift_window_frames == 0 || f.ela_drift_window_frames >= 2, "filter.ela_drift_window_frames",
           f.ela_drift_window_frames, "must be 0 (off) or at least 2");
  c->Check(f.ela_outside_frames_to_move >= 1, "filter.ela_outside_frames_to_move", f.ela_outside_frames_to_move,
           "must be at least 1");
  c->Check(f.ela_young_sightings >= 0, "filter.ela_young_sightings", f.ela_young_sightings,
           "must be at least 0 (0: off)");
  c->Check(f.ela_young_creep_share >= 0.0 && f.ela_young_creep_share <= 1.0, "filter.ela_young_creep_share",
           f.ela_young_creep_share, "must be in [0, 1]");
  c->Check(f.ela_drop_unseen_after_frames >= 1, "filter.ela_drop_unseen_after_frames", f.ela_drop_unseen_after_frames,
           "must be at least 1");
  c->Check(f.resample_ess_fraction >= 0.0 && f.resample_ess_fraction <= 1.0, "filter.resample_ess_fraction",
           f.resample_ess_fraction, "must be in [0, 1]");
  c->Check(f.odometry_scale > 0.0 && f.odometry_scale <= 2.0, "filter.odometry_scale", f.odometry_scale,
           "must be in (0, 2]");
  c->Check(f.odometry_turn_scale > 0.0 && f.odometry_turn_scale <= 2.0, "filter.odometry_turn_scale",
           f.odometry_turn_scale, "must be in (0, 2]");
  c->Check(f.outlier_gate_probability > 0.0 && f.outlier_gate_probability <= 1.0, "filter.outlier_gate_probability",
           f.outlier_gate_probability, "must be in (0, 1]");
  c->Check(f.odometry_lag_s >= 0.0 && f.odometry_lag_s <= 1.0, "filter.odometry_lag_s", f.odometry_lag_s,
           "must be in [0, 1]");
}

// The rendezvous detector and cooperation.
void CheckCooperation(const ScenarioOptions& o, Checker* c) {
  const auto& rendezvous = o.rendezvous;
  const auto& cooperation = o.cooperation;
  c->Check(rendezvous.enable_from_step >= 0, "rendezvous.enable_from_step", rendezvous.enable_from_step,
           "must not be negative");
  c->Check(rendezvous.window_steps >= 1, "rendezvous.window_steps", rendezvous.window_steps, "must be at least 1");
  c->Check(rendezvous.min_interval_steps >= 0, "rendezvous.min_interval_steps", rendezvous.min_interval_steps,
           "must not be negative");
  const auto& co = cooperation;
  c->Check(co.max_snapshot_landmarks >= 1 && co.max_snapshot_landmarks <= 100000, "cooperation.max_snapshot_landmarks",
           co.max_snapshot_landmarks, "must be in 1..100000");
  c->Check(co.min_seen_span_steps >= 0, "cooperation.min_seen_span_steps", co.min_seen_span_steps,
           "must not be negative");
  c->Check(co.match_gate_probability > 0.0 && co.match_gate_probability < 1.0, "cooperation.match_gate_probability",
           co.match_gate_probability, "must be in (0, 1)");
  c->Check(co.merge_min_separation_m >= 0.0, "cooperation.merge_min_separation_m", co.merge_min_separation_m,
           "must not be negative");
  c->Check(co.transform_gate_probability > 0.0 && co.transform_gate_probability < 1.0,
           "cooperation.transform_gate_probability", co.transform_gate_probability, "must be in (0, 1)");
  c->Check(co.max_history_steps >= 0 && co.max_history_steps <= 10000, "cooperation.max_history_steps",
           co.max_history_steps, "must be in 0..10000");
  c->Check(co.exchange_window_steps >= 1 && co.exchange_window_steps <= 100000, "cooperation.exchange_window_steps",
           co.exchange_window_steps, "must be in 1..100000");
  c->Check(co.max_batch_steps >= 1 && co.max_batch_steps <= 10000, "cooperation.max_batch_steps", co.max_batch_steps,
           "must be in 1..10000");
  c->Check(std::isfinite(co.joint_every_s) && co.joint_every_s >= 0.0, "cooperation.joint_every_s", co.joint_every_s,
           "must be >= 0 (0: only at the end)");
}

}  // namespace

bool ScenarioOptions::IsValid(std::string* error) const {
  Checker c(error);
  CheckRun(*this, &c);
  CheckRobots(*this, &c);
  CheckLandmarks(*this, &c);
  CheckSensors(*this, &c);
  CheckFilter(*this, &c);
  CheckCooperation(*this, &c);
  return c.ok();
}

void ApplyOverride(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ScenarioError("override '" + assignment + "' must have the form key.path=value");
  }
  const std::string path = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw ScenarioError("override '" + assignment + "': value is not valid YAML (" + e.msg + ")");
  }
  std::vector<std::string> keys;
  std::stringstream ss(path);
  for (std::string k; std::getline(ss, k, '.');) keys.push_back(k);
  // Walk with fresh handles (yaml-cpp node assignment rebinds, so never reassign a handle).
  // A scalar on the way has no children: name the prefix that holds it (yaml-cpp would throw
  // its own BadSubscript, which is not a ScenarioError).
  const auto reject_scalar = [&](const YAML::Node& node, std::size_t depth) {
    if (!node.IsScalar()) return;
    std::string prefix;
    for (std::size_t j = 0; j < depth; ++j) prefix += (j == 0 ? "" : ".") + keys[j];
    throw ScenarioError("override '" + path + "': '" + prefix + "' is a value, not a mapping or a list");
  };
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    YAML::Node cur = chain.back();
    reject_scalar(cur, i);
    const std::string& k = keys[i];
    if (cur.IsSequence()) {
      std::size_t idx = 0;
      try {
        idx = std::stoul(k);
      } catch (const std::exception&) {
        throw ScenarioError(
            std::string("override '").append(path).append("': '").append(k).append("' must be an index into a list"));
      }
      if (idx >= cur.size()) {
        throw ScenarioError(
            std::string("override '").append(path).append("': index ").append(k).append(" is out of range"));
      }
      chain.push_back(cur[idx]);
    } else {
      if (!cur[k]) cur[k] = YAML::Node(YAML::NodeType::Map);
      chain.push_back(cur[k]);
    }
  }
  YAML::Node parent = chain.back();
  reject_scalar(parent, keys.size() - 1);
  const std::string& last = keys.back();
  if (parent.IsSequence()) {
    std::size_t idx = 0;
    try {
      idx = std::stoul(last);
    } catch (const std::exception&) {
      throw ScenarioError("override '" + path + "': '" + last + "' must be an index into a list");
    }
    if (idx >= parent.size()) throw ScenarioError("override '" + path + "': index " + last + " is out of range");
    parent[idx] = value;
  } else {
    parent[last] = value;
  }
}

namespace {

// Throws for a mapping that names a key twice (YAML forbids it; yaml-cpp would keep the first)
// or whose key is not a plain name (a list or a mapping as a key).
void RejectDuplicateKeys(const YAML::Node& node, const std::string& path) {
  const auto child_path = [&](const std::string& key) { return path.empty() ? key : path + "." + key; };
  if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) RejectDuplicateKeys(node[i], child_path(std::to_string(i)));
  } else if (node.IsMap()) {
    std::set<std::string> keys;
    for (const auto& entry : node) {
      if (!entry.first.IsScalar()) {
        throw ScenarioError("scenario key '" + (path.empty() ? std::string("(top level)") : path) +
                            "' holds a key that is not a plain name");
      }
      const std::string key = entry.first.Scalar();
      if (!keys.insert(key).second) throw ScenarioError("scenario key '" + child_path(key) + "' appears twice");
      RejectDuplicateKeys(entry.second, child_path(key));
    }
  }
}

// The document of a scenario, without duplicate keys; `source` names it in errors.
template <typename Input>
YAML::Node ParseDocument(Input& input, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(input);
  } catch (const YAML::Exception& e) {
    throw ScenarioError(source + " is not valid YAML: " + e.what());
  }
  RejectDuplicateKeys(root, "");
  return root;
}

}  // namespace

ScenarioOptions ParseScenario(const std::string& yaml_text) {
  const YAML::Node root = ParseDocument(yaml_text, "the scenario");
  ScenarioOptions options = CreateScenarioOptions(root);
  std::string error;
  if (!options.IsValid(&error)) throw ScenarioError(error);
  return options;
}

ScenarioOptions LoadScenario(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path);
  if (!in) throw ScenarioError("cannot open scenario file '" + path + "'");
  YAML::Node root = ParseDocument(in, "scenario file '" + path + "'");
  for (const auto& o : overrides) ApplyOverride(root, o);
  ScenarioOptions options = CreateScenarioOptions(root);
  // A relative replay.dir from the file is relative to the file's folder; one given by an
  // override (--set replay.dir=...) is relative to the current directory.
  if (options.replay.enabled && !options.replay.dir.empty() && options.replay.dir[0] != '/') {
    bool from_override = false;
    for (const auto& o : overrides) from_override = from_override || o.rfind("replay.dir=", 0) == 0;
    if (!from_override) {
      const auto slash = path.find_last_of('/');
      if (slash != std::string::npos) options.replay.dir = path.substr(0, slash + 1) + options.replay.dir;
    }
  }
  std::string error;
  if (!options.IsValid(&error)) throw ScenarioError(error);
  return options;
}

std::set<std::string> ScenarioKeys(const std::vector<YAML::Node>& documents) {
  std::set<std::string> looked_up;
  struct Collecting {  // stops collecting however parsing ends
    explicit Collecting(std::set<std::string>* keys) { keys_looked_up = keys; }
    ~Collecting() { keys_looked_up = nullptr; }
    Collecting(const Collecting&) = delete;
    Collecting& operator=(const Collecting&) = delete;
  } collecting(&looked_up);
  for (const auto& document : documents) CreateScenarioOptions(document);
  std::set<std::string> leaves;
  for (const auto& key : looked_up) {
    const auto next = looked_up.upper_bound(key);
    const bool has_children = next != looked_up.end() && next->rfind(key, 0) == 0 && (next->size() > key.size()) &&
                              ((*next)[key.size()] == '.' || (*next)[key.size()] == '[');
    if (!has_children) leaves.insert(key);
  }
  return leaves;
}

}  // namespace mrslam::common
