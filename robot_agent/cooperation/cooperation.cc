#include "robot_agent/cooperation/cooperation.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <tuple>
#include <utility>

#include "common/angles.h"
#include "common/gaussian.h"
#include "robot_agent/filters/map_fusion.h"
#include "robot_agent/smoother/levenberg_marquardt.h"

// How an agent cooperates (the protocol; docs/cooperation.md):
//
//  * Detection. Every robot detection in the own scan at step k >= rendezvous.enable_from_step
//    is sent to the seen robot as a RelativeMeasurement (range, bearing, the own pose estimate
//    and covariance at k) and kept, with that pose, in a short history.
//  * Mutual detection. At the start of step k+1 the peer's measurements of step k arrive. An own
//    detection of j at step s and j's detection of this robot at step s' pair when
//    |s - s'| < window_steps, one to one, closest steps first. Both agents see the same
//    candidates at the same call (lockstep: messages of step k are applied at k+1), and the
//    pairing rule is symmetric in the two roles, so both find the same pairs.
//  * Encounter and rendezvous. Mutual detections at most window_steps apart form an encounter.
//    The first mutual detection of an encounter at least min_interval_steps after the previous
//    rendezvous of the pair (or the pair's first ever) is a rendezvous event; its transform is
//    refined by the encounter's mutual detections for 10 steps (the evaluator scores the
//    transform held at the end of that window) and a map snapshot goes to the peer in
//    AfterStep of the same step.
//  * Transform. Each mutual detection gives T(G_i <- G_j) (rendezvous.h) with a covariance split
//    into the robots' pose errors (dependent) and this detection's measurement noise
//    (independent). Repeated estimates are fused by split covariance intersection: the pose
//    errors of consecutive steps (and of later encounters) are strongly correlated (the same
//    drifting filters), so counting them as independent each time would shrink the covariance
//    without bound and make the transform overconfident; SCI treats their correlation as
//    unknown (never overconfident) while the measurement noise, truly independent per
//    detection, is still averaged down. Both agents fuse the same pairs in the same order from
//    the same numbers (each uses the pose the other sent and its own kept pose), so their
//    results are inverses of each other up to the linearization of the fusion.
//  * Maps. A snapshot holds the confirmed landmarks of the sender's estimate (at most
//    max_snapshot_landmarks) and the sender's transforms. The receiver first refines the
//    transform with it: it matches the sender's landmarks to its own confirmed ones (reported
//    identities, else the Mahalanobis gate through the held transform) and aligns the matched
//    pairs with the held transform as prior (AlignLandmarks, rendezvous.h), which uses every
//    landmark both robots know instead of one detection. Both agents send their snapshots in
//    the same step and align the same two maps, so their results stay inverses of each other
//    (up to linearization). Then it moves the landmarks into its frame with the refined
//    transform's covariance (map_fusion.h) and merges them into its filter, unless the last
//    mutual detection with the sender lay outside the transform gate of the one held: then one
//    of the two robots is off in its own frame by more than its covariance says (the frames'
//    transform is fixed), and the sender's map would not land where the transform puts it.
//    Transitive frames: from a snapshot of j holding T(G_j <- G_k), the receiver composes
//    T(G_i <- G_k) = T(G_i <- G_j) T(G_j <- G_k) for every k it did not know; a chained
//    transform is later refined (SCI) by newer chains or replaced in effect by meeting k. The
//    transforms also go on their own (a snapshot without landmarks) at every encounter that is
//    not a rendezvous, every kShareFramesSteps of a long encounter, and without map merging.
//  * Joint transform (cooperation.joint_transform). A fastslam agent's snapshot at a rendezvous
//    also carries its history since step 1 (odometry, scans with each landmark reading labelled
//    by its track). With both histories whole, the receiver labels the sender's readings of the
//    landmarks matched as above with its own tracks and computes the MAP estimate of both paths
//    and every labelled landmark's path (BatchSmoother); the sender's first pose so placed gives
//    T(G_self <- G_sender), with the first pose's covariance, and replaces the held transform
//    (the alignment is then skipped) unless it lies beyond transform_gate_probability of it.
//    Both sides solve the same problem from opposite anchors.
//  * Validation. Every message is checked before use: known other sender, addressed here, a step
//    not after the current one and not older than the last applied of its kind from that sender,
//    finite numbers, symmetric positive-definite covariances, a snapshot within the size bound
//    whose sender's frame is known. A failing message is counted and changes nothing.
//  * Cooperative localization (cooperation.cooperative_localization). Each mutual detection is
//    used once: those of the first 10 steps of a rendezvous refine the transform; later ones
//    (the rest of a long encounter, re-meetings before min_interval_steps) correct the own pose
//    when the own and the peer's detections are of the filter's current step. The peer's
//    position is moved into the own frame with the transform covariance added (that covariance
//    already holds this robot's own pose error at the rendezvous) and its covariance doubled:
//    the covariance-intersection bound with omega = 1/2 for the unknown correlation between the
//    two robots' estimates that earlier exchanges create.
namespace mrslam::robot_agent::cooperation {
namespace {

constexpr std::uint32_t kShareFramesSteps = 10;  // a long encounter passes on the frames known this often
constexpr std::size_t kMaxHistory = 64;          // bound of each per-peer detection history
constexpr double kCovarianceFloor = 1e-10;       // added to a sent pose covariance (1 particle: 0)

bool Finite(const common::Pose2& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.heading); }

bool ValidLandmark(const filters::MapLandmark& l) {
  return l.mean.allFinite() && std::isfinite(l.v_mps) && std::isfinite(l.w_radps) &&
         common::IsSymmetricPositiveDefinite<3>(l.covariance);
}

bool ValidTransform(const FrameTransform& t) {
  return Finite(t.t_self_peer) && common::IsSymmetricPositiveDefinite<3>(t.covariance);
}

// The landmarks a snapshot carries: the confirmed ones of the estimate, those of the own robot
// (self_index) only once seen over options.min_seen_span_steps, the most recently seen first
// when options.max_snapshot_landmarks cuts. The alignment selects the own map the same way, so
// that both sides of a rendezvous align the same two sets of landmarks.
std::vector<filters::MapLandmark> SnapshotLandmarks(const filters::FilterEstimate& estimate, int self_index,
                                                    const CooperationOptions& options) {
  std::vector<const filters::MapLandmark*> confirmed;
  for (const auto& l : estimate.landmarks) {
    const bool seen_long =
        l.origin_robot != self_index ||
        l.last_seen_step >= l.first_seen_step + static_cast<std::uint32_t>(options.min_seen_span_steps);
    if (!l.tentative && seen_long && ValidLandmark(l)) confirmed.push_back(&l);
  }
  std::stable_sort(confirmed.begin(), confirmed.end(),
                   [](const filters::MapLandmark* a, const filters::MapLandmark* b) {
                     return a->last_seen_step > b->last_seen_step;
                   });
  if (confirmed.size() > static_cast<std::size_t>(options.max_snapshot_landmarks)) {
    confirmed.resize(options.max_snapshot_landmarks);
  }
  std::vector<filters::MapLandmark> out;
  out.reserve(confirmed.size());
  for (const filters::MapLandmark* l : confirmed) out.push_back(*l);
  return out;
}

// A map's heading of a landmark (its direction of travel) constrains an alignment when the
// landmark moves and its heading is known better than half the variance of a uniform heading
// (pi^2 / 3, what the filters report for an unknown one).
bool HeadingKnown(const filters::MapLandmark& l) {
  return l.moving && l.covariance(2, 2) < common::kPi * common::kPi / 6.0;
}

filters::MatchCandidate Candidate(const filters::MapLandmark& l) {
  return {l.mean.head<2>(), l.covariance.topLeftCorner<2, 2>(), l.landmark_id};
}

template <typename Map>
void TrimToSize(Map* m, std::size_t size) {
  while (m->size() > size) m->erase(m->begin());
}

}  // namespace

Cooperation::Cooperation(const AgentOptions& options)
    : options_(options),
      robot_id_(options.robot_id),
      self_index_(options.TeamIndex(options.robot_id)),
      var_range_(options.sensors.lidar.range_noise_sd_m * options.sensors.lidar.range_noise_sd_m),
      var_bearing_(options.sensors.lidar.bearing_noise_sd_rad * options.sensors.lidar.bearing_noise_sd_rad),
      exchange_(options),
      streamed_(options) {
  // A noiseless lidar still needs a usable measurement covariance.
  var_range_ = std::max(var_range_, 1e-12);
  var_bearing_ = std::max(var_bearing_, 1e-12);
  first_pose_ = options.initial_pose;
}

const std::vector<RendezvousEvent>& Cooperation::rendezvous() const { return rendezvous_; }

std::vector<FrameTransform> Cooperation::known_transforms() const {
  std::vector<FrameTransform> out;
  for (const auto& [peer, state] : peers_) {
    if (!state.transform) continue;
    out.push_back({peer, state.transform_step, state.transform->t, state.transform->Covariance()});
  }
  return out;
}

std::vector<std::string> Cooperation::frames_known() const {
  std::vector<std::string> out;
  for (const auto& [peer, state] : peers_) {
    if (state.transform) out.push_back(peer);
  }
  return out;
}

std::map<std::string, std::uint32_t> Cooperation::data_held() const {
  std::map<std::string, std::uint32_t> out;
  for (const auto& [peer, state] : peers_) {
    if (state.last_snapshot_step) out[peer] = *state.last_snapshot_step;
  }
  for (const auto& [origin, log] : exchange_.logs()) {
    if (origin != robot_id_ && log.Held() > 0) out[origin] = std::max(out[origin], log.Held());
  }
  return out;
}

int Cooperation::rejected_messages() const { return rejected_; }

bool Cooperation::HeaderValid(const PeerHeader& h) const {
  if (h.recipient != robot_id_) return false;
  if (h.sender == robot_id_ || options_.TeamIndex(h.sender) < 0) return false;
  // Messages of step k are applied at the start of k+1, after AfterStep(k) of this agent.
  if (any_step_ && h.step > last_step_ + 1) return false;
  return std::isfinite(h.time_s);
}

bool Cooperation::MeasurementValid(const RelativeMeasurement& m) const {
  if (!HeaderValid(m.header)) return false;
  if (!std::isfinite(m.bearing_rad) || !Finite(m.sender_pose)) return false;
  if (m.has_range && !(std::isfinite(m.range_m) && m.range_m > 0.0)) return false;
  return common::IsSymmetricPositiveDefinite<3>(m.sender_covariance);
}

bool Cooperation::SnapshotValid(const MapSnapshot& m) const {
  if (!HeaderValid(m.header)) return false;
  if (static_cast<int>(m.landmarks.size()) > options_.cooperation.max_snapshot_landmarks) return false;
  if (m.known_transforms.size() > options_.team.size()) return false;
  const int robots = static_cast<int>(options_.team.size());
  for (const auto& l : m.landmarks) {
    if (!ValidLandmark(l) || l.origin_robot < -1 || l.origin_robot >= robots) return false;
  }
  for (const auto& t : m.known_transforms) {
    if (options_.TeamIndex(t.peer) < 0 || t.peer == m.header.sender || !ValidTransform(t)) return false;
  }
  return HistoryValid(m);
}

bool Cooperation::HistoryValid(const MapSnapshot& m) const {
  if (m.history.empty()) return true;
  // Every step from 1 to the snapshot's, within the bound; finite readings; labels, not -1.
  if (m.history.size() > static_cast<std::size_t>(options_.cooperation.max_history_steps) ||
      m.history.size() != m.header.step || !Finite(m.first_pose)) {
    return false;
  }
  for (std::size_t i = 0; i < m.history.size(); ++i) {
    if (!SharedStepValid(m.history[i], static_cast<std::uint32_t>(i + 1))) return false;
  }
  return true;
}

void Cooperation::Receive(const PeerInbox& inbox, filters::SlamFilter* filter) {
  // 1. Relative measurements: validate and keep them for pairing.
  for (const auto& m : inbox.measurements) {
    if (!MeasurementValid(m)) {
      Reject();
      continue;
    }
    PeerState& peer = peers_[m.header.sender];
    // Stale: older than the last applied from that sender; a second one of the same step is a
    // duplicate.
    if (peer.last_measurement_step && m.header.step <= *peer.last_measurement_step) {
      RejectStale();
      continue;
    }
    peer.last_measurement_step = m.header.step;
    if (static_cast<int>(m.header.step) >= options_.rendezvous.enable_from_step) {
      peer.peer_measurements[m.header.step] = m;
      TrimToSize(&peer.peer_measurements, kMaxHistory);
    }
  }
  // 2. Mutual detections, per peer in id order.
  for (auto& [id, peer] : peers_) {
    if (!peer.peer_measurements.empty()) PairMutualDetections(id, filter);
  }
  // 3. Map snapshots (after the transforms of this call are known); first those held until the
  //    sender's frame became known.
  ApplyEarlyMessages(filter);
  for (const auto& m : inbox.maps) {
    if (!SnapshotValid(m)) {
      Reject();
      continue;
    }
    PeerState& sender = peers_[m.header.sender];
    if (!sender.transform) {
      HoldEarlySnapshot(&sender, m);
      continue;
    }
    ApplySnapshotInOrder(m, filter);
  }
  // 4. Landmark-moved notices.
  for (const auto& n : inbox.moved) {
    PeerState* peer = HeaderValid(n.header) ? &peers_[n.header.sender] : nullptr;
    if (peer == nullptr || !n.position_in_sender.allFinite()) {
      Reject();
      continue;
    }
    if (!peer->transform) {
      HoldEarlyNotice(peer, n);
      continue;
    }
    ApplyNoticeInOrder(n, filter);
  }
  // 5. Raw measurements shared: each batch whole or not at all.
  for (const auto& b : inbox.factors) {
    if (!options_.cooperation.share_factors || !HeaderValid(b.header) || !exchange_.Receive(b)) Reject();
  }
}

void Cooperation::ApplyEarlyMessages(filters::SlamFilter* filter) {
  for (auto& [id, peer] : peers_) {
    if (!peer.transform) continue;
    if (peer.early_snapshot) {
      const MapSnapshot m = std::move(*peer.early_snapshot);
      peer.early_snapshot.reset();
      ApplySnapshotInOrder(m, filter);
    }
    const std::vector<LandmarkMovedNotice> notices = std::move(peer.early_notices);
    peer.early_notices.clear();
    for (const auto& n : notices) ApplyNoticeInOrder(n, filter);
  }
}

void Cooperation::HoldEarlySnapshot(PeerState* peer, const MapSnapshot& m) {
  if (!peer->early_snapshot || m.header.step >= peer->early_snapshot->header.step) peer->early_snapshot = m;
}

void Cooperation::HoldEarlyNotice(PeerState* peer, const LandmarkMovedNotice& n) {
  peer->early_notices.push_back(n);
  if (peer->early_notices.size() > kMaxEarlyNotices) peer->early_notices.erase(peer->early_notices.begin());
}

void Cooperation::ApplySnapshotInOrder(const MapSnapshot& m, filters::SlamFilter* filter) {
  if (InOrder(&peers_[m.header.sender].last_snapshot_step, m.header.step)) ApplySnapshot(m, filter);
}

bool Cooperation::InOrder(std::optional<std::uint32_t>* last_step, std::uint32_t step) {
  if (*last_step && step < **last_step) {
    RejectStale();
    return false;
  }
  *last_step = step;
  return true;
}

void Cooperation::ApplyNoticeInOrder(const LandmarkMovedNotice& n, filters::SlamFilter* filter) {
  // The position moves into the own frame through the transform to the sender,
  // p = R(theta) p_s + t, with covariance J_T Sigma_T J_T^T (J_T = d p / d(t, theta)); the filter
  // drops the landmark it gates to (filters that track motion ignore notices).
  PeerState& peer = peers_[n.header.sender];
  if (!InOrder(&peer.last_notice_step, n.header.step)) return;
  ++moved_notices_;
  const common::Pose2& t = peer.transform->t;
  const Eigen::Vector2d p = common::TransformPoint(t, n.position_in_sender);
  Eigen::Matrix<double, 2, 3> j;
  j << 1.0, 0.0, -(p.y() - t.y), 0.0, 1.0, p.x() - t.x;
  const Eigen::Matrix2d cov = j * peer.transform->Covariance() * j.transpose();
  filter->ApplyMovedNotice(p, cov, options_.cooperation.match_gate_probability);
}

void Cooperation::PairMutualDetections(const std::string& peer_id, filters::SlamFilter* filter) {
  PeerState& peer = peers_[peer_id];
  const auto window = static_cast<std::int64_t>(options_.rendezvous.window_steps);
  // Candidate pairs (own step s, peer step t), |s - t| < window, ordered by a key that is the
  // same from both sides: (|s - t|, s + t, the step of the robot with the smaller id).
  const bool self_first = robot_id_ < peer_id;
  std::vector<std::tuple<std::int64_t, std::int64_t, std::int64_t, std::uint32_t, std::uint32_t>> candidates;
  for (const auto& [t, theirs] : peer.peer_measurements) {
    for (const auto& [s, own] : peer.own_detections) {
      const std::int64_t gap = std::abs(static_cast<std::int64_t>(s) - static_cast<std::int64_t>(t));
      if (gap >= window) continue;
      candidates.emplace_back(gap, static_cast<std::int64_t>(s) + t, self_first ? s : t, s, t);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  std::vector<std::uint32_t> used_own, used_peer;
  for (const auto& c : candidates) {
    const std::uint32_t s = std::get<3>(c), t = std::get<4>(c);
    if (std::count(used_own.begin(), used_own.end(), s) || std::count(used_peer.begin(), used_peer.end(), t)) {
      continue;
    }
    used_own.push_back(s);
    used_peer.push_back(t);
    pairs.emplace_back(s, t);
  }
  // Apply in time order (the later step of the pair, then the own step ordered symmetrically).
  std::sort(pairs.begin(), pairs.end(), [&](const auto& a, const auto& b) {
    const auto key = [&](const auto& p) {
      return std::make_tuple(std::max(p.first, p.second), self_first ? p.first : p.second);
    };
    return key(a) < key(b);
  });
  for (const auto& [s, t] : pairs) {
    ApplyMutualDetection(peer_id, s, peer.own_detections.at(s), peer.peer_measurements.at(t), filter);
    peer.own_detections.erase(s);
    peer.peer_measurements.erase(t);
  }
  // Unpaired entries that no future detection (step >= last_step_ + 1) can pair with.
  const std::int64_t oldest = static_cast<std::int64_t>(last_step_) + 1 - window;
  for (auto it = peer.peer_measurements.begin(); it != peer.peer_measurements.end();) {
    it = static_cast<std::int64_t>(it->first) < oldest ? peer.peer_measurements.erase(it) : std::next(it);
  }
}

void Cooperation::ApplyMutualDetection(const std::string& peer_id, std::uint32_t own_step, const OwnDetection& own,
                                       const RelativeMeasurement& theirs, filters::SlamFilter* filter) {
  PeerState& peer = peers_[peer_id];
  const auto& rv = options_.rendezvous;
  const std::uint32_t step = std::max(own_step, theirs.header.step);

  // Encounter bookkeeping.
  const bool continues = peer.in_encounter && step <= peer.encounter_last + static_cast<std::uint32_t>(rv.window_steps);
  if (!continues) {
    peer.in_encounter = true;
    peer.encounter_first = step;
    peer.encounter_pairs = 0;
    peer.event_index = -1;
    const bool due = !peer.last_rendezvous_step ||
                     step >= *peer.last_rendezvous_step + static_cast<std::uint32_t>(rv.min_interval_steps);
    if (due) {
      peer.last_rendezvous_step = step;
      peer.event_index = static_cast<int>(rendezvous_.size());
      rendezvous_.push_back({peer_id, step, {}, Eigen::Matrix3d::Identity()});
      peer.snapshot_due = options_.cooperation.merge_maps;
    }
    // Every encounter passes on the frames known (chaining needs no map): at a rendezvous with
    // the map, at any other encounter (or without map merging) on their own.
    peer.transforms_due = !peer.snapshot_due;
  }
  if (continues && (step - peer.encounter_first) % kShareFramesSteps == 0) peer.transforms_due = true;
  peer.encounter_last = step;
  ++peer.encounter_pairs;
  const bool refines = Refining(peer, step);

  const MutualDetection z{own.range_m, own.bearing_rad, theirs.range_m, theirs.bearing_rad, theirs.has_range};
  const TransformEstimate estimate = TransformFromMutual(own.pose, own.covariance, theirs.sender_pose,
                                                         theirs.sender_covariance, z, var_range_, var_bearing_);
  if (!estimate.t.Vector().allFinite() || !estimate.Covariance().allFinite()) return;

  const bool localize = options_.cooperation.cooperative_localization && !refines && peer.transform &&
                        own_step == theirs.header.step && own_step == last_step_ && filter != nullptr;
  if (localize) {
    // The peer's position in the own frame: Compose(T, pose_j), covariance through the
    // transform and the peer's pose, doubled (see the comment at the top).
    const common::Pose2 in_own = common::Compose(peer.transform->t, theirs.sender_pose);
    const Eigen::Matrix3d jt = common::ComposeJacobianLeft(peer.transform->t, theirs.sender_pose);
    const Eigen::Matrix3d jp = common::ComposeJacobianRight(peer.transform->t, theirs.sender_pose);
    const Eigen::Matrix3d c =
        jt * peer.transform->Covariance() * jt.transpose() + jp * theirs.sender_covariance * jp.transpose();
    const double gate = common::ChiSquare2Quantile(options_.cooperation.transform_gate_probability);
    if (filter->ObserveKnownRobot(in_own.Translation(), 2.0 * c.topLeftCorner<2, 2>(), own.range_m, own.bearing_rad,
                                  gate)) {
      ++cooperative_updates_;
    }
    return;
  }

  TransformEstimate held = estimate;
  if (peer.transform) {
    // An estimate far outside the one held (e.g. a detection paired with the wrong robot) is
    // not fused.
    const double gate = ChiSquare3Quantile(options_.cooperation.transform_gate_probability);
    const bool fuse = !peer.met || TransformDistanceSquared(*peer.transform, estimate) <= gate;
    held = fuse ? FuseSplitCi(*peer.transform, estimate) : *peer.transform;
    peer.last_detection_outlier = !fuse;
  }
  peer.met = true;
  HoldTransform(&peer, held, step);
}

bool Cooperation::Refining(const PeerState& peer, std::uint32_t step) const {
  return peer.event_index >= 0 && WithinRefinement(peer.encounter_first, step);
}

void Cooperation::HoldTransform(PeerState* peer, const TransformEstimate& t, std::uint32_t step) {
  peer->transform = t;
  peer->transform_step = step;
  if (Refining(*peer, step)) {
    RendezvousEvent& e = rendezvous_[peer->event_index];
    e.t_self_peer = t.t;
    e.covariance = t.Covariance();
  }
}

Cooperation::CommonLandmarks Cooperation::MatchSnapshot(const MapSnapshot& m, const filters::FilterEstimate& own,
                                                        const TransformEstimate& held) const {
  // Moving landmarks are compared only when both maps hold them at the same step (a snapshot is
  // predicted to its own step).
  const bool same_step = own.step == m.header.step;
  // A landmark that came from the other side (by provenance) is that side's estimate seen
  // through the transform held when it was merged: it would only confirm that transform.
  const int sender_index = options_.TeamIndex(m.header.sender);
  const Eigen::Matrix3d t_cov = held.Covariance();
  CommonLandmarks out;
  std::vector<filters::MatchCandidate> mine_c, theirs_c;
  for (const auto& l : SnapshotLandmarks(own, self_index_, options_.cooperation)) {
    if ((!same_step && l.moving) || l.origin_robot == sender_index) continue;
    out.mine.push_back(l);
    mine_c.push_back(Candidate(l));
  }
  for (const auto& l : m.landmarks) {
    if ((!same_step && l.moving) || l.origin_robot == self_index_) continue;
    out.theirs.push_back(l);
    theirs_c.push_back(Candidate(filters::TransformLandmark(l, held.t, t_cov)));
  }
  out.match = filters::MatchLandmarks(mine_c, theirs_c,
                                      common::ChiSquare2Quantile(options_.cooperation.match_gate_probability));
  return out;
}

void Cooperation::LinkTracks(const CommonLandmarks& common, PeerState* sender) const {
  for (std::size_t i = 0; i < common.theirs.size(); ++i) {
    const filters::MapLandmark& l = common.theirs[i];
    if (l.track_id > static_cast<std::uint32_t>(std::numeric_limits<int>::max())) continue;
    const int track = static_cast<int>(l.track_id);
    std::optional<int> seen_moving;
    if (const auto it = sender->tracks.find(track); it != sender->tracks.end() && it->second.kinematics >= 0) {
      seen_moving = it->second.kinematics;
    }
    const auto k = KeptKinematics(seen_moving, TrackKinematics(options_.filter, l));
    if (!k) continue;
    sender->tracks[track] = {common.match[i] < 0 ? 0 : common.mine[common.match[i]].track_id, *k};
  }
}

PeerTrackLinks Cooperation::track_links() const {
  PeerTrackLinks out;
  for (const auto& [peer, state] : peers_) {
    if (!state.tracks.empty()) out[peer] = state.tracks;
  }
  return out;
}

void Cooperation::AlignWithSnapshot(const MapSnapshot& m, const CommonLandmarks& common, PeerState* sender) {
  std::vector<LandmarkPair> pairs;
  for (std::size_t i = 0; i < common.match.size(); ++i) {
    if (common.match[i] < 0) continue;
    const filters::MapLandmark& a = common.mine[common.match[i]];
    const filters::MapLandmark& b = common.theirs[i];
    pairs.push_back({a.mean, a.covariance, b.mean, b.covariance, HeadingKnown(a) && HeadingKnown(b)});
  }
  if (const auto aligned = AlignLandmarks(*sender->transform, pairs)) HoldTransform(sender, *aligned, m.header.step);
}

std::optional<smoother::BatchSmoother::Kinematics> Cooperation::JointKinematics(const filters::MapLandmark& l) const {
  const auto k = TrackKinematics(options_.filter, l);
  if (!k) return std::nullopt;
  return KinematicsOf(options_.filter, *k);
}

std::optional<TransformEstimate> Cooperation::JointTransform(const MapSnapshot& m, const filters::FilterEstimate& own,
                                                             const CommonLandmarks& common,
                                                             const TransformEstimate& held) const {
  // Both histories whole and of the same steps.
  if (!JointPossible() || m.history.empty() || own.step != m.header.step || history_.size() != m.history.size()) {
    return std::nullopt;
  }
  // Labels: the own tracks as they are; the sender's matched to an own landmark take its label,
  // the others one of their own above every own track.
  std::map<int, smoother::BatchSmoother::Kinematics> kinematics;
  std::map<int, int> own_label, their_label;  // track -> label
  for (const auto& l : common.mine) {
    if (const auto k = JointKinematics(l)) {
      kinematics[static_cast<int>(l.track_id)] = *k;
      own_label[static_cast<int>(l.track_id)] = static_cast<int>(l.track_id);
    }
  }
  int next_label = kinematics.empty() ? 1 : kinematics.rbegin()->first + 1;
  int shared = 0;  // landmarks both robots read: without one, only the mutual detections tie the paths
  for (std::size_t i = 0; i < common.theirs.size(); ++i) {
    const filters::MapLandmark& l = common.theirs[i];
    const int own_track = common.match[i] < 0 ? -1 : static_cast<int>(common.mine[common.match[i]].track_id);
    if (own_track >= 0 && own_label.count(own_track) != 0) {
      their_label[static_cast<int>(l.track_id)] = own_track;
      ++shared;
    } else if (const auto k = JointKinematics(l)) {
      kinematics[next_label] = *k;
      their_label[static_cast<int>(l.track_id)] = next_label++;
    }
  }
  if (shared == 0) return std::nullopt;
  // The sender's first pose in the own frame, started from the held transform.
  smoother::BatchSmoother joint(options_,
                                {{robot_id_, first_pose_}, {m.header.sender, common::Compose(held.t, m.first_pose)}},
                                kinematics, options_.rendezvous.enable_from_step);
  // Each solve ends where the cost stops falling, as the online smoother's do.
  joint.SetRelativeCostTolerance(smoother::LeastSquares{}.min_relative_decrease);
  // Solved as it grows, so that each solve starts near its answer: after 5 steps, then whenever
  // the history has grown by a quarter (at least 5 steps), and at the end; a few dozen solves
  // for hundreds of steps.
  std::size_t next_solve = 5;
  for (std::size_t t = 0; t < history_.size(); ++t) {
    joint.Add({Relabelled(history_[t], own_label), Relabelled(m.history[t], their_label)});
    if (t + 1 == next_solve || t + 1 == history_.size()) {
      joint.Solve();
      next_solve = std::max(next_solve + 5, (t + 1) * 5 / 4);
    }
  }
  // T(G_self <- G_sender) = first pose of the sender in the own frame * inverse(its first pose
  // in its own frame).
  const common::Pose2 first_inverse = common::Inverse(m.first_pose);
  TransformEstimate out;
  out.t = common::Compose(joint.FirstPose(1), first_inverse);
  const Eigen::Matrix3d j = common::ComposeJacobianLeft(joint.FirstPose(1), first_inverse);
  out.dependent = j * joint.FirstPoseCovariance(1) * j.transpose();
  out.dependent = 0.5 * (out.dependent + out.dependent.transpose()).eval();
  const double gate = ChiSquare3Quantile(options_.cooperation.transform_gate_probability);
  if (!Finite(out.t) || !common::IsSymmetricPositiveDefinite<3>(out.dependent) ||
      TransformDistanceSquared(held, out) > gate) {
    return std::nullopt;
  }
  return out;
}

void Cooperation::Share(const common::SensorStep& step, const filters::FilterEstimate& estimate,
                        const std::optional<common::SensorStep>& labelled) {
  const bool by_identity = options_.sensors.lidar.report_identity;
  const auto shared = by_identity ? LabelledStep(step, estimate, true) : labelled;
  if (!shared) return;
  const bool stream = options_.cooperation.stream_landmarks;
  exchange_.RecordOwn(*shared, stream ? TrackEstimates(step, estimate, by_identity) : std::vector<TrackEstimate>{});
  if (stream) streamed_.Observe(estimate);
}

void Cooperation::CompleteMap(filters::FilterEstimate* estimate) const {
  if (options_.cooperation.share_factors && options_.cooperation.stream_landmarks) {
    streamed_.Append(exchange_.logs(), known_transforms(), estimate);
  }
}

void Cooperation::Record(const common::SensorStep& step, const filters::FilterEstimate& estimate) {
  // The history for the joint transform keeps the own tracks (JointTransform labels by them); the
  // steps shared are labelled by identity where the sensor reports one.
  const std::optional<common::SensorStep> labelled = LabelledStep(step, estimate, false);
  if (options_.cooperation.share_factors) Share(step, estimate, labelled);
  const bool fits = labelled && step.lidar.stamp.step == history_.size() + 1 &&
                    history_.size() < static_cast<std::size_t>(options_.cooperation.max_history_steps);
  if (!history_usable_ || !fits) {
    history_usable_ = false;
    history_.clear();
    return;
  }
  history_.push_back(*labelled);
}

void Cooperation::ApplySnapshot(const MapSnapshot& m, filters::SlamFilter* filter) {
  PeerState& sender = peers_[m.header.sender];
  if (filter != nullptr) {
    const filters::FilterEstimate own = filter->Estimate();
    const CommonLandmarks common = MatchSnapshot(m, own, *sender.transform);
    if (JointAmongMovers(options_)) LinkTracks(common, &sender);
    if (const auto joint = JointTransform(m, own, common, *sender.transform)) {
      HoldTransform(&sender, *joint, m.header.step);
      joint_estimates_.push_back({m.header.sender, m.header.step, joint->t, joint->Covariance()});
    } else {
      AlignWithSnapshot(m, common, &sender);
    }
  }
  const TransformEstimate& t_self_sender = *sender.transform;
  // Transitive frames: T(G_self <- G_k) = T(G_self <- G_sender) * T(G_sender <- G_k).
  for (const auto& ft : m.known_transforms) {
    if (ft.peer == robot_id_) continue;
    PeerState& k = peers_[ft.peer];
    if (k.met) continue;  // met directly: its own detections are better than a chain
    TransformEstimate sender_k;
    sender_k.t = ft.t_self_peer;
    sender_k.dependent = ft.covariance;
    const TransformEstimate chained = ChainTransforms(t_self_sender, sender_k);
    k.transform = k.transform ? FuseSplitCi(*k.transform, chained) : chained;
    k.transform_step = m.header.step;
  }
  if (!options_.cooperation.merge_maps || filter == nullptr || m.landmarks.empty() || sender.last_detection_outlier) {
    return;
  }
  std::vector<filters::MapLandmark> moved;
  moved.reserve(m.landmarks.size());
  const Eigen::Matrix3d t_cov = t_self_sender.Covariance();
  for (const auto& l : m.landmarks) {
    // The own landmarks coming back (by provenance) carry nothing new: not merged again. Nor
    // are moving landmarks whose motion the sender estimates (constant turn rate): the model
    // holds only until the landmark turns or stops, and a landmark the receiver has not seen
    // would be predicted by it until it leaves the map.
    const bool estimated_mover = l.moving && l.motion == filters::LandmarkMotionKind::kConstantTurnRate;
    if (l.origin_robot != self_index_ && !estimated_mover) {
      moved.push_back(filters::TransformLandmark(l, t_self_sender.t, t_cov));
    }
  }
  if (moved.empty()) return;
  filter->MergeLandmarks(moved, options_.cooperation.map_fusion, options_.cooperation.match_gate_probability,
                         options_.cooperation.merge_min_separation_m);
}

MapSnapshot Cooperation::MakeSnapshot(const std::string& peer, const filters::FilterEstimate& estimate,
                                      bool with_map) const {
  MapSnapshot m;
  m.header = {robot_id_, peer, estimate.step, estimate.time_s, 0};
  if (with_map) m.landmarks = SnapshotLandmarks(estimate, self_index_, options_.cooperation);
  if (with_map && JointPossible()) {
    m.first_pose = first_pose_;
    m.history = history_;
  }
  for (const auto& t : known_transforms()) {
    if (t.peer != peer) m.known_transforms.push_back(t);
  }
  return m;
}

std::vector<LandmarkMovedNotice> Cooperation::MovedNotices(const std::vector<filters::MovedLandmark>& moved,
                                                           std::uint32_t step, double time_s) const {
  std::vector<LandmarkMovedNotice> notices;
  for (const auto& [id, peer] : peers_) {
    if (!peer.transform) continue;
    for (const auto& m : moved) {
      if (!m.position.allFinite()) continue;
      LandmarkMovedNotice n;
      n.header = {robot_id_, id, step, time_s, 0};
      n.track_id = m.track_id;
      n.landmark_id = m.landmark_id;
      n.position_in_sender = m.position;
      notices.push_back(n);
    }
  }
  return notices;
}

PeerOutbox Cooperation::AfterStep(const common::SensorStep& step, const filters::FilterEstimate& estimate) {
  PeerOutbox out;
  const common::LidarScan& scan = step.lidar;
  Record(step, estimate);
  const std::uint32_t k = estimate.step;
  last_step_ = k;
  any_step_ = true;
  const auto& rv = options_.rendezvous;
  Eigen::Matrix3d covariance = 0.5 * (estimate.covariance + estimate.covariance.transpose());
  covariance.diagonal().array() += kCovarianceFloor;
  if (static_cast<int>(k) >= rv.enable_from_step && Finite(estimate.pose) && covariance.allFinite()) {
    for (const auto& d : scan.robots) {
      if (d.seen_robot_id == robot_id_ || options_.TeamIndex(d.seen_robot_id) < 0) continue;
      if (!std::isfinite(d.range_m) || !std::isfinite(d.bearing_rad) || d.range_m <= 0.0) continue;
      PeerState& peer = peers_[d.seen_robot_id];
      if (!peer.own_detections.emplace(k, OwnDetection{d.range_m, d.bearing_rad, estimate.pose, covariance}).second) {
        continue;  // a second detection of the same robot in one scan
      }
      TrimToSize(&peer.own_detections, kMaxHistory);
      RelativeMeasurement m;
      m.header = {robot_id_, d.seen_robot_id, k, estimate.time_s, 0};
      m.has_range = true;
      m.range_m = d.range_m;
      m.bearing_rad = d.bearing_rad;
      m.sender_pose = estimate.pose;
      m.sender_covariance = covariance;
      out.measurements.push_back(m);
    }
  }
  // Own detections that no future peer measurement (step >= k + 1... received from k on) can
  // pair with: the next Receive brings peer steps >= k, so keep s > k - window.
  const std::int64_t oldest = static_cast<std::int64_t>(k) - rv.window_steps;
  for (auto& [id, peer] : peers_) {
    for (auto it = peer.own_detections.begin(); it != peer.own_detections.end();) {
      it = static_cast<std::int64_t>(it->first) <= oldest ? peer.own_detections.erase(it) : std::next(it);
    }
    const bool with_map = peer.snapshot_due;
    if (with_map || (peer.transforms_due && peer.transform)) {
      MapSnapshot m = MakeSnapshot(id, estimate, with_map);
      if (with_map || !m.known_transforms.empty()) out.maps.push_back(std::move(m));
    }
    peer.snapshot_due = false;
    peer.transforms_due = false;
  }
  if (options_.cooperation.share_factors) out.factors = exchange_.Outgoing(k, estimate.time_s);
  return out;
}

}  // namespace mrslam::robot_agent::cooperation
