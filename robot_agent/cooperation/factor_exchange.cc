#include "robot_agent/cooperation/factor_exchange.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <set>

#include "common/gaussian.h"

namespace mrslam::robot_agent::cooperation {
namespace {

constexpr std::size_t kMaxItems = 256;  // per step and kind: a scan of a few hundred detections at most

bool FinitePose(const common::Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.heading); }

bool Reading(double range_m, double bearing_rad, double time_s) {
  return std::isfinite(range_m) && range_m > 0.0 && std::isfinite(bearing_rad) && std::isfinite(time_s);
}

// The label a detection of track `track` (0: none) is shared with, 0 when it is left out.
std::uint32_t Label(const common::LandmarkDetection& d, std::uint32_t track, bool by_identity) {
  if (by_identity && d.landmark_id >= 0) return static_cast<std::uint32_t>(d.landmark_id) + 1;
  return track;
}

// Whether a landmark reading of step s carries label.
bool NamesLabel(const common::SensorStep& s, std::uint32_t label) {
  return std::any_of(s.lidar.landmarks.begin(), s.lidar.landmarks.end(),
                     [&](const common::LandmarkDetection& d) { return d.landmark_id == static_cast<int>(label); });
}

// Keeps t as its label's newest estimate in tracks, at most kMaxTracksHeld labels (the label
// whose estimate is oldest let go).
void Keep(const TrackEstimate& t, std::map<std::uint32_t, TrackEstimate>* tracks) {
  (*tracks)[t.label] = t;
  if (tracks->size() <= kMaxTracksHeld) return;
  tracks->erase(std::min_element(tracks->begin(), tracks->end(),
                                 [](const auto& a, const auto& b) { return a.second.step < b.second.step; }));
}

// A value rounded to single precision.
double Single(double x) { return static_cast<double>(static_cast<float>(x)); }

}  // namespace

std::optional<common::SensorStep> LabelledStep(const common::SensorStep& step, const filters::FilterEstimate& estimate,
                                               bool by_identity) {
  if (!estimate.labels_detections || estimate.detection_tracks.size() != step.lidar.landmarks.size()) {
    return std::nullopt;
  }
  common::SensorStep kept;
  kept.lidar.stamp = step.lidar.stamp;
  kept.lidar.robots = step.lidar.robots;
  kept.odometry = step.odometry;
  for (std::size_t i = 0; i < step.lidar.landmarks.size(); ++i) {
    common::LandmarkDetection d = step.lidar.landmarks[i];
    // By identity: the identity the sensor reports + 1, the same for every robot.
    const std::uint32_t label = Label(d, estimate.detection_tracks[i], by_identity);
    if (label == 0) continue;
    d.landmark_id = static_cast<int>(label);
    kept.lidar.landmarks.push_back(d);
  }
  return kept;
}

std::vector<TrackEstimate> TrackEstimates(const common::SensorStep& step, const filters::FilterEstimate& estimate,
                                          bool by_identity) {
  std::vector<TrackEstimate> out;
  if (!estimate.labels_detections || estimate.detection_tracks.size() != step.lidar.landmarks.size()) return out;
  std::set<std::uint32_t> labels;
  for (std::size_t i = 0; i < step.lidar.landmarks.size(); ++i) {
    const std::uint32_t track = estimate.detection_tracks[i];
    const std::uint32_t label = Label(step.lidar.landmarks[i], track, by_identity);
    // By identity, a detection without one names no landmark every robot knows.
    const bool unnamed = by_identity && step.lidar.landmarks[i].landmark_id < 0;
    if (track == 0 || label == 0 || unnamed || !labels.insert(label).second) continue;
    const auto l = std::find_if(estimate.landmarks.begin(), estimate.landmarks.end(),
                                [&](const filters::MapLandmark& m) { return m.track_id == track; });
    if (l == estimate.landmarks.end() || l->tentative) continue;
    out.push_back({label, step.lidar.stamp.step, l->mean, l->covariance.topLeftCorner<2, 2>(), l->covariance(2, 2),
                   l->v_mps, l->w_radps, l->moving});
  }
  return out;
}

std::int32_t TimeOffsetUs(double time_s, double step_time_s) {
  const double us = std::round((time_s - step_time_s) * 1e6);
  if (!std::isfinite(us)) return 0;
  return static_cast<std::int32_t>(std::clamp(us, -double{kMaxTimeOffsetUs}, double{kMaxTimeOffsetUs}));
}

double OffsetTime(double step_time_s, std::int32_t offset_us) { return step_time_s + offset_us * 1e-6; }

common::SensorStep SharedPrecision(common::SensorStep step) {
  const double t0 = step.lidar.stamp.time_s;
  const auto offset = [&](double t) { return OffsetTime(t0, TimeOffsetUs(t, t0)); };
  step.odometry.stamp = step.lidar.stamp;
  for (auto& o : step.odometry.segments) o = {offset(o.time_s), Single(o.dt_s), Single(o.v_mps), Single(o.w_radps)};
  const auto reading = [&](auto& d) {
    d.time_s = offset(d.time_s);
    d.range_m = Single(d.range_m);
    d.bearing_rad = Single(d.bearing_rad);
  };
  for (auto& d : step.lidar.landmarks) reading(d);
  for (auto& d : step.lidar.robots) reading(d);
  return step;
}

TrackEstimate SharedPrecision(TrackEstimate t) {
  t.mean = t.mean.unaryExpr(&Single);
  t.position_covariance = t.position_covariance.unaryExpr(&Single);
  t.heading_var = Single(t.heading_var);
  t.v_mps = Single(t.v_mps);
  t.w_radps = Single(t.w_radps);
  return t;
}

bool TrackEstimateValid(const TrackEstimate& t, std::uint32_t first, std::uint32_t last) {
  const auto within = [](double x, double bound) { return std::isfinite(x) && std::abs(x) <= bound; };
  return t.label >= 1 && t.label <= kMaxTrackLabel && t.step >= first && t.step <= last &&
         within(t.mean.x(), kMaxTrackCoordinateM) && within(t.mean.y(), kMaxTrackCoordinateM) &&
         std::isfinite(t.mean.z()) && within(t.v_mps, kMaxTrackRate) && within(t.w_radps, kMaxTrackRate) &&
         within(t.heading_var, kMaxTrackVariance) && t.heading_var >= 0.0 &&
         t.position_covariance.cwiseAbs().maxCoeff() <= kMaxTrackVariance &&
         common::IsSymmetricPositiveDefinite<2>(t.position_covariance);
}

bool SharedStepValid(const common::SensorStep& s, std::uint32_t step) {
  if (s.lidar.stamp.step != step || !std::isfinite(s.lidar.stamp.time_s)) return false;
  if (s.odometry.segments.size() > kMaxItems || s.lidar.landmarks.size() > kMaxItems ||
      s.lidar.robots.size() > kMaxItems || !s.imu.readings.empty()) {
    return false;
  }
  for (const auto& o : s.odometry.segments) {
    if (!std::isfinite(o.v_mps) || !std::isfinite(o.w_radps) || !std::isfinite(o.time_s) ||
        !(std::isfinite(o.dt_s) && o.dt_s >= 0.0)) {
      return false;
    }
  }
  for (const auto& d : s.lidar.landmarks) {
    if (d.landmark_id < 1 || !Reading(d.range_m, d.bearing_rad, d.time_s)) return false;
  }
  for (const auto& d : s.lidar.robots) {
    if (d.seen_robot_id.empty() || !Reading(d.range_m, d.bearing_rad, d.time_s)) return false;
  }
  return true;
}

FactorExchange::FactorExchange(const AgentOptions& options) : options_(options), self_(options.robot_id) {
  logs_[self_].first_pose = options.initial_pose;
}

std::uint32_t FactorExchange::Held(const std::string& origin) const {
  const auto it = logs_.find(origin);
  return it == logs_.end() ? 0 : it->second.Held();
}

std::size_t FactorExchange::HeldBytes() const {
  std::size_t bytes = 0;
  for (const auto& [origin, log] : logs_) {
    Counted& counted = counted_[origin];
    if (counted.steps > log.steps.size()) counted = {};
    for (; counted.steps < log.steps.size(); ++counted.steps) {
      const common::SensorStep& s = log.steps[counted.steps];
      counted.bytes += filters::ElementBytes(s.lidar.landmarks) + filters::ElementBytes(s.lidar.robots) +
                       filters::ElementBytes(s.odometry.segments);
    }
    bytes += filters::ElementBytes(log.steps) + counted.bytes + log.tracks.size() * sizeof(TrackEstimate);
  }
  return bytes;
}

void FactorExchange::RecordOwn(const common::SensorStep& labelled, const std::vector<TrackEstimate>& tracks) {
  FactorLog& own = logs_[self_];
  const std::uint32_t k = labelled.lidar.stamp.step;
  if (!own_growing_ || k != own.Held() + 1) {
    own_growing_ = false;
    return;
  }
  own.steps.push_back(SharedPrecision(labelled));
  for (const TrackEstimate& t : tracks) {
    const auto held = own.tracks.find(t.label);
    if (held != own.tracks.end() && !t.moving && t.step < held->second.step + kTrackRefreshSteps) continue;
    const TrackEstimate shared = SharedPrecision(t);
    if (TrackEstimateValid(shared, k, k) && NamesLabel(own.steps.back(), t.label)) Keep(shared, &own.tracks);
  }
  if (static_cast<int>(k) < options_.rendezvous.enable_from_step) return;
  for (const auto& d : labelled.lidar.robots) {
    if (d.seen_robot_id != self_ && options_.TeamIndex(d.seen_robot_id) >= 0) detected_at_[d.seen_robot_id] = k;
  }
}

std::vector<std::string> FactorExchange::SendOrder() const {
  std::vector<std::string> order{self_};
  if (!options_.cooperation.relay_factors) return order;
  for (const auto& id : options_.team) {
    if (id != self_ && logs_.count(id) > 0) order.push_back(id);
  }
  return order;
}

std::uint32_t FactorExchange::SendFrom(const std::string& peer, const std::string& origin) {
  const std::uint32_t holds = peer_holdings_[peer][origin].steps;
  auto& sends = sends_[peer][origin];
  if (sends.empty()) return holds;
  // The newest send the peer's newest batch must reflect.
  const auto heard = holdings_step_.find(peer);
  auto covered = sends.end();
  if (heard != holdings_step_.end() && heard->second >= kAckLagSteps) {
    const auto after = sends.upper_bound(heard->second - kAckLagSteps);
    if (after != sends.begin()) covered = std::prev(after);
  }
  if (covered != sends.end() && holds < covered->second) {
    sends.clear();  // lost: from what it holds
    return holds;
  }
  if (covered != sends.end()) sends.erase(sends.begin(), covered);
  constexpr std::size_t kMaxSendsKept = 64;  // without news from the peer, the newest only matter
  while (sends.size() > kMaxSendsKept) sends.erase(sends.begin());
  return std::max(holds, sends.rbegin()->second);
}

bool FactorExchange::FedByAnother(const std::string& peer, const std::string& origin, std::uint32_t k) {
  const FactorHolding& h = peer_holdings_[peer][origin];
  const auto heard = holdings_step_.find(peer);
  // h.fed_at is a step of the feeder's; the robots step together, so it compares with k.
  return !h.fed_by.empty() && h.fed_by != self_ && heard != holdings_step_.end() && h.fed_at + kAckLagSteps + 1 >= k;
}

void FactorExchange::AddRuns(const std::string& peer, std::uint32_t k, FactorBatch* batch) {
  auto budget = static_cast<std::size_t>(options_.cooperation.max_batch_steps);
  for (const auto& origin : SendOrder()) {
    if (origin == peer || budget == 0) continue;
    const FactorLog& log = logs_.at(origin);
    const std::uint32_t from = SendFrom(peer, origin);
    if (from >= log.Held()) continue;
    if (origin != self_ && (log.Held() - from <= kRelayLagSteps || FedByAnother(peer, origin, k))) continue;
    const std::uint32_t to = std::min<std::uint32_t>(log.Held(), from + static_cast<std::uint32_t>(budget));
    FactorRun run{origin, from + 1, log.first_pose, {}, {}};
    run.steps.assign(log.steps.begin() + from, log.steps.begin() + to);
    for (const auto& [label, t] : log.tracks) {
      if (t.step > from && t.step <= to) run.tracks.push_back(t);
    }
    if (run.tracks.size() > kMaxItems) {  // the newest go
      std::stable_sort(run.tracks.begin(), run.tracks.end(),
                       [](const auto& a, const auto& b) { return a.step > b.step; });
      run.tracks.resize(kMaxItems);
    }
    budget -= run.steps.size();
    steps_sent_ += run.steps.size();
    sends_[peer][origin][k] = to;
    batch->runs.push_back(std::move(run));
  }
}

std::optional<FactorBatch> FactorExchange::BatchFor(const std::string& peer, std::uint32_t k, double time_s) {
  if (last_batch_[peer] + 1 < k) session_start_[peer] = k;  // a new session
  FactorBatch batch;
  batch.header = {self_, peer, k, time_s, 0};
  batch.opened_by_step = detected_at_.at(peer);
  for (const auto& [origin, log] : logs_) batch.holdings.push_back({origin, log.Held(), log.fed_by, log.fed_at});
  const auto heard = holdings_step_.find(peer);
  const bool news = heard != holdings_step_.end() && heard->second >= session_start_[peer];
  const bool greeting = !news && k <= session_start_[peer] + kAckLagSteps;
  if (!greeting) AddRuns(peer, k, &batch);
  if (batch.runs.empty() && !greeting) return std::nullopt;
  if (options_.cooperation.relay_factors) AddHeard(peer, k, &batch);
  const FactorRun* own = batch.runs.empty() || batch.runs.front().origin != self_ ? nullptr : &batch.runs.front();
  const bool carried = own != nullptr && batch.opened_by_step >= own->first_step &&
                       batch.opened_by_step - own->first_step < own->steps.size();
  if (!carried && peer_holdings_[peer][self_].steps < batch.opened_by_step) {
    batch.opening.push_back(logs_.at(self_).steps.at(batch.opened_by_step - 1));
  }
  last_batch_[peer] = k;
  return batch;
}

void FactorExchange::AddHeard(const std::string& peer, std::uint32_t k, FactorBatch* batch) {
  auto& passed = heard_passed_[peer];
  for (const auto& [robot, step] : holdings_step_) {
    if (robot == peer || robot == self_) continue;
    const auto before = passed.find(robot);
    if (before != passed.end() && (step <= before->second.step || k < before->second.at + kHeardSteps)) continue;
    std::vector<FactorHolding> holdings;
    for (const auto& [origin, h] : peer_holdings_.at(robot)) holdings.push_back({origin, h.steps, h.fed_by, h.fed_at});
    batch->heard.push_back({robot, step, std::move(holdings)});
    passed[robot] = {step, k};
  }
}

std::vector<FactorBatch> FactorExchange::Outgoing(std::uint32_t k, double time_s) {
  std::vector<FactorBatch> out;
  for (const auto& [peer, at] : detected_at_) {
    if (at > k || k - at > static_cast<std::uint32_t>(options_.cooperation.exchange_window_steps)) continue;
    if (auto batch = BatchFor(peer, k, time_s)) out.push_back(std::move(*batch));
  }
  return out;
}

bool FactorExchange::BatchValid(const FactorBatch& b) const {
  const auto& co = options_.cooperation;
  if (b.opened_by_step == 0 || b.opened_by_step > b.header.step ||
      b.header.step - b.opened_by_step > static_cast<std::uint32_t>(co.exchange_window_steps)) {
    return false;
  }
  if (b.runs.size() > options_.team.size() || !HoldingsValid(b.holdings, b.header.step) || !HeardValid(b)) return false;
  std::set<std::string> seen;
  std::size_t steps = 0;
  for (const auto& run : b.runs) {
    if (options_.TeamIndex(run.origin) < 0 || run.origin == self_ || !seen.insert(run.origin).second) return false;
    if (run.origin != b.header.sender && !co.relay_factors) return false;
    if (run.first_step == 0 || !FinitePose(run.first_pose)) return false;
    steps += run.steps.size();
    if (steps > static_cast<std::size_t>(co.max_batch_steps)) return false;
    for (std::size_t i = 0; i < run.steps.size(); ++i) {
      if (!SharedStepValid(run.steps[i], run.first_step + static_cast<std::uint32_t>(i))) return false;
    }
    if (!TracksValid(run)) return false;
  }
  return b.opening.size() <= 1 && (b.opening.empty() || SharedStepValid(b.opening[0], b.opened_by_step));
}

bool FactorExchange::HoldingsValid(const std::vector<FactorHolding>& holdings, std::uint32_t step) const {
  if (holdings.size() > options_.team.size()) return false;
  // The robots step together: nobody holds more steps of an origin, or was fed at a later step, than the
  // report's step, give or take a window's skew.
  const std::uint64_t latest =
      std::uint64_t{step} + static_cast<std::uint64_t>(options_.cooperation.exchange_window_steps);
  std::set<std::string> seen;
  return std::all_of(holdings.begin(), holdings.end(), [&](const FactorHolding& h) {
    return options_.TeamIndex(h.origin) >= 0 && seen.insert(h.origin).second &&
           (h.fed_by.empty() || options_.TeamIndex(h.fed_by) >= 0) && h.steps <= latest && h.fed_at <= latest;
  });
}

bool FactorExchange::HeardValid(const FactorBatch& b) const {
  if (b.heard.empty()) return true;
  if (!options_.cooperation.relay_factors || b.heard.size() > options_.team.size()) return false;
  std::set<std::string> seen;
  return std::all_of(b.heard.begin(), b.heard.end(), [&](const HeardHoldings& h) {
    return options_.TeamIndex(h.robot) >= 0 && h.robot != b.header.sender && h.robot != self_ &&
           seen.insert(h.robot).second && h.step > 0 && h.step <= b.header.step && HoldingsValid(h.holdings, h.step);
  });
}

void FactorExchange::Hear(const std::string& robot, std::uint32_t step, const std::vector<FactorHolding>& holdings) {
  const auto heard = holdings_step_.find(robot);
  if (robot == self_ || (heard != holdings_step_.end() && step < heard->second)) return;
  holdings_step_[robot] = step;
  auto& held = peer_holdings_[robot];
  held.clear();
  for (const auto& h : holdings) held[h.origin] = h;
}

bool FactorExchange::TracksValid(const FactorRun& run) {
  if (run.tracks.empty()) return true;
  if (run.tracks.size() > kMaxItems || run.steps.empty()) return false;
  const auto last = run.first_step + static_cast<std::uint32_t>(run.steps.size()) - 1;
  std::set<std::uint32_t> labels;
  for (const auto& t : run.tracks) {
    if (!TrackEstimateValid(t, run.first_step, last) || !labels.insert(t.label).second ||
        !NamesLabel(run.steps[t.step - run.first_step], t.label)) {
      return false;
    }
  }
  return true;
}

const common::SensorStep* FactorExchange::Opening(const FactorBatch& b) const {
  const auto held = logs_.find(b.header.sender);
  if (held != logs_.end() && b.opened_by_step <= held->second.Held()) return &held->second.steps[b.opened_by_step - 1];
  for (const auto& run : b.runs) {
    if (run.origin == b.header.sender && b.opened_by_step >= run.first_step &&
        b.opened_by_step - run.first_step < run.steps.size()) {
      return &run.steps[b.opened_by_step - run.first_step];
    }
  }
  return b.opening.empty() ? nullptr : &b.opening.front();
}

void FactorExchange::Apply(const FactorRun& run, const PeerHeader& from) {
  FactorLog& log = logs_[run.origin];
  const std::uint32_t held = log.Held();
  if (run.first_step > held + 1) {
    ++gaps_;
    return;
  }
  if (held == 0) log.first_pose = run.first_pose;
  const std::size_t skip = held + 1 - run.first_step;
  steps_again_ += std::min(skip, run.steps.size());
  if (skip >= run.steps.size()) return;
  log.steps.insert(log.steps.end(), run.steps.begin() + static_cast<std::ptrdiff_t>(skip), run.steps.end());
  for (const TrackEstimate& t : run.tracks) {
    const auto held_track = log.tracks.find(t.label);
    if (t.step > held && (held_track == log.tracks.end() || held_track->second.step < t.step)) Keep(t, &log.tracks);
  }
  log.fed_by = from.sender;
  log.fed_at = from.step;
  steps_received_ += run.steps.size() - skip;
}

bool FactorExchange::Receive(const FactorBatch& batch) {
  if (!BatchValid(batch)) return false;
  const common::SensorStep* opening = Opening(batch);
  if (opening == nullptr) {
    ++gaps_;  // the step that opened it was lost on the way
    return true;
  }
  const auto& seen = opening->lidar.robots;
  if (std::none_of(seen.begin(), seen.end(), [&](const common::RobotDetection& d) { return d.seen_robot_id == self_; }))
    return false;
  Hear(batch.header.sender, batch.header.step, batch.holdings);
  // A robot's batches of one step all say the same: a word of the step already heard changes nothing.
  for (const auto& h : batch.heard) Hear(h.robot, h.step, h.holdings);
  for (const auto& run : batch.runs) Apply(run, batch.header);
  return true;
}

}  // namespace mrslam::robot_agent::cooperation
