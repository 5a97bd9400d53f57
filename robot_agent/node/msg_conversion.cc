#include "robot_agent/node/msg_conversion.h"

#include "common/dds/msg_conversion.h"
#include "robot_agent/cooperation/factor_exchange.h"

namespace mrslam::robot_agent {
namespace {

msg::HistoryStep ToHistoryStep(const common::SensorStep& step) {
  msg::HistoryStep h;
  h.lidar(dds::ToMsg(step.lidar));
  h.odometry(dds::ToMsg(step.odometry));
  return h;
}
common::SensorStep FromHistoryStep(const msg::HistoryStep& h) {
  common::SensorStep step;
  step.lidar = dds::FromMsg(h.lidar());
  step.odometry = dds::FromMsg(h.odometry());
  return step;
}

// A reading's time, range and bearing in their shared form.
template <typename M, typename D>
M SharedReading(const D& d, double step_time_s) {
  M m;
  m.time_offset_us(cooperation::TimeOffsetUs(d.time_s, step_time_s));
  m.range_m(static_cast<float>(d.range_m));
  m.bearing_rad(static_cast<float>(d.bearing_rad));
  return m;
}

// A step in its shared form (cooperation::SharedPrecision) and back: exact both ways.
msg::SharedStep ToSharedStep(const common::SensorStep& step) {
  const double t0 = step.lidar.stamp.time_s;
  msg::SharedStep m;
  m.time_s(t0);
  for (const auto& o : step.odometry.segments) {
    msg::SharedSegment s;
    s.time_offset_us(cooperation::TimeOffsetUs(o.time_s, t0));
    s.dt_s(static_cast<float>(o.dt_s));
    s.v_mps(static_cast<float>(o.v_mps));
    s.w_radps(static_cast<float>(o.w_radps));
    m.odometry().push_back(s);
  }
  for (const auto& d : step.lidar.landmarks) {
    auto r = SharedReading<msg::SharedLandmarkReading>(d, t0);
    r.label(d.landmark_id);
    m.landmarks().push_back(r);
  }
  for (const auto& d : step.lidar.robots) {
    auto r = SharedReading<msg::SharedRobotReading>(d, t0);
    r.seen_robot_id(d.seen_robot_id);
    m.robots().push_back(std::move(r));
  }
  return m;
}
msg::SharedTrack ToSharedTrack(const cooperation::TrackEstimate& t) {
  msg::SharedTrack m;
  m.label(t.label);
  m.step(t.step);
  m.x_m(static_cast<float>(t.mean.x()));
  m.y_m(static_cast<float>(t.mean.y()));
  m.heading_rad(static_cast<float>(t.mean.z()));
  m.cov_xx(static_cast<float>(t.position_covariance(0, 0)));
  m.cov_xy(static_cast<float>(t.position_covariance(0, 1)));
  m.cov_yy(static_cast<float>(t.position_covariance(1, 1)));
  m.heading_var(static_cast<float>(t.heading_var));
  m.v_mps(static_cast<float>(t.v_mps));
  m.w_radps(static_cast<float>(t.w_radps));
  m.moving(t.moving);
  return m;
}

cooperation::TrackEstimate FromSharedTrack(const msg::SharedTrack& m) {
  cooperation::TrackEstimate t;
  t.label = m.label();
  t.step = m.step();
  t.mean = {m.x_m(), m.y_m(), m.heading_rad()};
  t.position_covariance << m.cov_xx(), m.cov_xy(), m.cov_xy(), m.cov_yy();
  t.heading_var = m.heading_var();
  t.v_mps = m.v_mps();
  t.w_radps = m.w_radps();
  t.moving = m.moving();
  return t;
}

common::SensorStep FromSharedStep(const msg::SharedStep& m, const std::string& origin, std::uint32_t step_number) {
  const double t0 = m.time_s();
  common::SensorStep step;
  step.lidar.stamp = {origin, step_number, t0};
  step.odometry.stamp = step.lidar.stamp;
  for (const auto& o : m.odometry()) {
    step.odometry.segments.push_back(
        {cooperation::OffsetTime(t0, o.time_offset_us()), o.dt_s(), o.v_mps(), o.w_radps()});
  }
  for (const auto& d : m.landmarks()) {
    step.lidar.landmarks.push_back(
        {cooperation::OffsetTime(t0, d.time_offset_us()), d.range_m(), d.bearing_rad(), d.label()});
  }
  for (const auto& d : m.robots()) {
    step.lidar.robots.push_back(
        {cooperation::OffsetTime(t0, d.time_offset_us()), d.range_m(), d.bearing_rad(), d.seen_robot_id()});
  }
  return step;
}

msg::Stamp HeaderStamp(const cooperation::PeerHeader& h) {
  return dds::ToMsg(common::Stamp{h.sender, h.step, h.time_s});
}
cooperation::PeerHeader HeaderFrom(const msg::Stamp& s, const std::string& recipient, std::uint32_t sequence) {
  return {s.robot_id(), recipient, s.step(), s.time_s(), sequence};
}
// The header every peer message carries: the sender's stamp, the recipient, the sequence number.
template <typename M>
void PutHeader(const cooperation::PeerHeader& h, M* m) {
  m->stamp(HeaderStamp(h));
  m->recipient_id(h.recipient);
  m->sequence_number(h.sequence);
}

std::vector<msg::FactorHolding> HoldingsMsg(const std::vector<cooperation::FactorHolding>& holdings) {
  std::vector<msg::FactorHolding> out;
  out.reserve(holdings.size());
  for (const auto& h : holdings) {
    msg::FactorHolding mh;
    mh.origin_id(h.origin);
    mh.steps(h.steps);
    mh.fed_by(h.fed_by);
    mh.fed_at(h.fed_at);
    out.push_back(std::move(mh));
  }
  return out;
}
std::vector<cooperation::FactorHolding> HoldingsFrom(const std::vector<msg::FactorHolding>& holdings) {
  std::vector<cooperation::FactorHolding> out;
  out.reserve(holdings.size());
  for (const auto& h : holdings) out.push_back({h.origin_id(), h.steps(), h.fed_by(), h.fed_at()});
  return out;
}

}  // namespace

msg::LandmarkEstimate ToMsg(const filters::MapLandmark& l) {
  msg::LandmarkEstimate m;
  m.track_id(l.track_id);
  m.landmark_id(l.landmark_id);
  m.pose(dds::ToMsg(common::Pose2{l.mean.x(), l.mean.y(), l.mean.z()}));
  m.covariance(dds::CovarianceToMsg(l.covariance));
  m.v_mps(l.v_mps);
  m.w_radps(l.w_radps);
  m.motion_model(static_cast<std::uint8_t>(l.motion));
  m.moving(l.moving);
  m.tentative(l.tentative);
  m.last_seen_step(l.last_seen_step);
  m.origin_robot(static_cast<std::int16_t>(l.origin_robot));
  m.origin_track(l.origin_track);
  return m;
}

filters::MapLandmark FromMsg(const msg::LandmarkEstimate& m) {
  filters::MapLandmark l;
  l.track_id = m.track_id();
  l.landmark_id = m.landmark_id();
  l.mean = {m.pose().x_m(), m.pose().y_m(), m.pose().heading_rad()};
  l.covariance = dds::CovarianceFromMsg(m.covariance());
  l.v_mps = m.v_mps();
  l.w_radps = m.w_radps();
  l.motion = static_cast<filters::LandmarkMotionKind>(m.motion_model());
  l.moving = m.moving();
  l.tentative = m.tentative();
  l.last_seen_step = m.last_seen_step();
  l.origin_robot = m.origin_robot();
  l.origin_track = m.origin_track();
  return l;
}

msg::RendezvousEvent ToMsg(const cooperation::RendezvousEvent& e) {
  msg::RendezvousEvent m;
  m.peer_id(e.peer);
  m.step(e.step);
  m.t_self_peer(dds::ToMsg(e.t_self_peer));
  m.covariance(dds::CovarianceToMsg(e.covariance));
  return m;
}
cooperation::RendezvousEvent FromMsg(const msg::RendezvousEvent& m) {
  return {m.peer_id(), m.step(), dds::FromMsg(m.t_self_peer()), dds::CovarianceFromMsg(m.covariance())};
}
msg::RendezvousEvent ToMsg(const cooperation::FrameTransform& t) {
  return ToMsg(cooperation::RendezvousEvent{t.peer, t.step, t.t_self_peer, t.covariance});
}
cooperation::FrameTransform TransformFromMsg(const msg::RendezvousEvent& m) {
  return {m.peer_id(), m.step(), dds::FromMsg(m.t_self_peer()), dds::CovarianceFromMsg(m.covariance())};
}

msg::Estimate ToMsg(const filters::FilterEstimate& e, const std::string& robot_id, const std::string& filter) {
  msg::Estimate m;
  m.stamp(dds::ToMsg(common::Stamp{robot_id, e.step, e.time_s}));
  m.filter(filter);
  m.pose(dds::ToMsg(e.pose));
  m.covariance(dds::CovarianceToMsg(e.covariance));
  m.effective_sample_size(e.effective_sample_size);
  m.particles(static_cast<std::uint32_t>(e.particles));
  for (const auto& l : e.landmarks) m.landmarks().push_back(ToMsg(l));
  return m;
}

filters::FilterEstimate FromMsg(const msg::Estimate& m) {
  filters::FilterEstimate e;
  e.step = m.stamp().step();
  e.time_s = m.stamp().time_s();
  e.pose = dds::FromMsg(m.pose());
  e.covariance = dds::CovarianceFromMsg(m.covariance());
  e.effective_sample_size = m.effective_sample_size();
  e.particles = static_cast<int>(m.particles());
  for (const auto& ml : m.landmarks()) e.landmarks.push_back(FromMsg(ml));
  return e;
}

msg::RelativeMeasurement ToMsg(const cooperation::RelativeMeasurement& r) {
  msg::RelativeMeasurement m;
  PutHeader(r.header, &m);
  m.has_range(r.has_range);
  m.range_m(r.range_m);
  m.bearing_rad(r.bearing_rad);
  m.sender_pose(dds::ToMsg(r.sender_pose));
  m.sender_covariance(dds::CovarianceToMsg(r.sender_covariance));
  return m;
}
cooperation::RelativeMeasurement FromMsg(const msg::RelativeMeasurement& m) {
  cooperation::RelativeMeasurement r;
  r.header = HeaderFrom(m.stamp(), m.recipient_id(), m.sequence_number());
  r.has_range = m.has_range();
  r.range_m = m.range_m();
  r.bearing_rad = m.bearing_rad();
  r.sender_pose = dds::FromMsg(m.sender_pose());
  r.sender_covariance = dds::CovarianceFromMsg(m.sender_covariance());
  return r;
}

std::vector<msg::DataHeld> DataHeldMsg(const std::map<std::string, std::uint32_t>& held) {
  std::vector<msg::DataHeld> out;
  for (const auto& [robot, steps] : held) {
    msg::DataHeld m;
    m.robot_id(robot);
    m.steps(steps);
    out.push_back(std::move(m));
  }
  return out;
}

msg::FactorBatch ToMsg(const cooperation::FactorBatch& b) {
  msg::FactorBatch m;
  PutHeader(b.header, &m);
  m.opened_by_step(b.opened_by_step);
  m.holdings(HoldingsMsg(b.holdings));
  for (const auto& h : b.heard) {
    msg::HeardHoldings mh;
    mh.robot_id(h.robot);
    mh.step(h.step);
    mh.holdings(HoldingsMsg(h.holdings));
    m.heard().push_back(std::move(mh));
  }
  for (const auto& r : b.runs) {
    msg::FactorRun mr;
    mr.origin_id(r.origin);
    mr.first_step(r.first_step);
    mr.first_pose(dds::ToMsg(r.first_pose));
    for (const auto& step : r.steps) mr.steps().push_back(ToSharedStep(step));
    for (const auto& t : r.tracks) mr.tracks().push_back(ToSharedTrack(t));
    m.runs().push_back(std::move(mr));
  }
  for (const auto& step : b.opening) m.opening().push_back(ToSharedStep(step));
  return m;
}
cooperation::FactorBatch FromMsg(const msg::FactorBatch& m) {
  cooperation::FactorBatch b;
  b.header = HeaderFrom(m.stamp(), m.recipient_id(), m.sequence_number());
  b.opened_by_step = m.opened_by_step();
  b.holdings = HoldingsFrom(m.holdings());
  for (const auto& h : m.heard()) b.heard.push_back({h.robot_id(), h.step(), HoldingsFrom(h.holdings())});
  for (const auto& mr : m.runs()) {
    cooperation::FactorRun r{mr.origin_id(), mr.first_step(), dds::FromMsg(mr.first_pose()), {}, {}};
    for (const auto& h : mr.steps()) {
      r.steps.push_back(FromSharedStep(h, r.origin, r.first_step + static_cast<std::uint32_t>(r.steps.size())));
    }
    for (const auto& t : mr.tracks()) r.tracks.push_back(FromSharedTrack(t));
    b.runs.push_back(std::move(r));
  }
  for (const auto& h : m.opening()) b.opening.push_back(FromSharedStep(h, b.header.sender, b.opened_by_step));
  return b;
}

msg::MapSnapshot ToMsg(const cooperation::MapSnapshot& s) {
  msg::MapSnapshot m;
  PutHeader(s.header, &m);
  for (const auto& l : s.landmarks) m.landmarks().push_back(ToMsg(l));
  for (const auto& t : s.known_transforms) m.known_transforms().push_back(ToMsg(t));
  m.first_pose(dds::ToMsg(s.first_pose));
  for (const auto& step : s.history) m.history().push_back(ToHistoryStep(step));
  return m;
}
cooperation::MapSnapshot FromMsg(const msg::MapSnapshot& m) {
  cooperation::MapSnapshot s;
  s.header = HeaderFrom(m.stamp(), m.recipient_id(), m.sequence_number());
  for (const auto& l : m.landmarks()) s.landmarks.push_back(FromMsg(l));
  for (const auto& t : m.known_transforms()) s.known_transforms.push_back(TransformFromMsg(t));
  s.first_pose = dds::FromMsg(m.first_pose());
  for (const auto& h : m.history()) s.history.push_back(FromHistoryStep(h));
  return s;
}

msg::LandmarkMovedNotice ToMsg(const cooperation::LandmarkMovedNotice& n) {
  msg::LandmarkMovedNotice m;
  PutHeader(n.header, &m);
  m.track_id(n.track_id);
  m.landmark_id(n.landmark_id);
  m.position_in_sender(dds::ToMsg(common::Pose2{n.position_in_sender.x(), n.position_in_sender.y(), 0.0}));
  return m;
}
cooperation::LandmarkMovedNotice FromMsg(const msg::LandmarkMovedNotice& m) {
  cooperation::LandmarkMovedNotice n;
  n.header = HeaderFrom(m.stamp(), m.recipient_id(), m.sequence_number());
  n.track_id = m.track_id();
  n.landmark_id = m.landmark_id();
  n.position_in_sender = {m.position_in_sender().x_m(), m.position_in_sender().y_m()};
  return n;
}

std::vector<msg::FinalTrajectory> FinalTrajectoryChunks(const std::vector<std::pair<int, common::Pose2>>& path,
                                                        const std::map<std::uint32_t, double>& step_times,
                                                        const common::Stamp& stamp) {
  const std::size_t chunks = (path.size() + kFinalTrajectoryChunkPoses - 1) / kFinalTrajectoryChunkPoses;
  std::vector<msg::FinalTrajectory> out(chunks);
  for (std::size_t c = 0; c < chunks; ++c) {
    out[c].stamp(dds::ToMsg(stamp));
    out[c].chunk(static_cast<std::uint32_t>(c));
    out[c].chunks(static_cast<std::uint32_t>(chunks));
  }
  for (std::size_t i = 0; i < path.size(); ++i) {
    const auto& [step, pose] = path[i];
    msg::TrajectoryPose p;
    p.step(static_cast<std::uint32_t>(step));
    const auto t = step_times.find(static_cast<std::uint32_t>(step));
    p.time_s(t == step_times.end() ? 0.0 : t->second);
    p.pose(dds::ToMsg(pose));
    out[i / kFinalTrajectoryChunkPoses].poses().push_back(p);
  }
  return out;
}

}  // namespace mrslam::robot_agent
