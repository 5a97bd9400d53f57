#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "robot_agent/cooperation/factor_exchange.h"
#include "robot_agent/cooperation/joint_chains.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/cooperation/rendezvous.h"
#include "robot_agent/cooperation/streamed_landmarks.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"
#include "robot_agent/smoother/batch_smoother.h"

namespace mrslam::robot_agent::cooperation {

// An agent's side of the cooperation among robots (paper A step 4, for N robots): the
// rendezvous detector, the frame transforms to peers (estimated from mutual range-bearing
// measurements, refined over an encounter, chained through peers' transforms), the map
// snapshots it sends and the merging of the snapshots it receives into its filter, and the
// validation of everything a peer sends. Pure: plain structs in and out; the node moves them.
//
// Per step k the node calls, in this order:
//   1. Receive(inbox of step k-1, filter)   peer messages sent during step k-1, in a fixed order
//   2. filter->Process(step k)
//   3. AfterStep(step k, estimate k)         -> the outbox of step k
class Cooperation {
 public:
  explicit Cooperation(const AgentOptions& options);

  // Validates and applies peer messages. Rejected messages are counted and leave the map unchanged.
  void Receive(const PeerInbox& inbox, filters::SlamFilter* filter);

  // Decides what to send after step k: relative measurements to every robot detected in the
  // scan (from rendezvous.enable_from_step on), map snapshots to peers at a new rendezvous.
  // Keeps the step (odometry, scan labelled by estimate.detection_tracks) in the own history.
  PeerOutbox AfterStep(const common::SensorStep& step, const filters::FilterEstimate& estimate);

  // "Landmark moved" notices for every peer whose frame is known (paper B, peer to peer instead
  // of through a leader), for the landmarks the filter saw move during the step.
  std::vector<LandmarkMovedNotice> MovedNotices(const std::vector<filters::MovedLandmark>& moved, std::uint32_t step,
                                                double time_s) const;

  // Whether an estimate made at step still refines the rendezvous of an encounter that began at
  // encounter_first: its transform is refined over the encounter's first kEncounterRefineSteps
  // steps (docs/metrics.md: scored after them), then held as it is in rendezvous().
  static bool WithinRefinement(std::uint32_t encounter_first, std::uint32_t step) {
    return step <= encounter_first + kEncounterRefineSteps;
  }

  // Every rendezvous so far (for the estimate stream and the log), and the frames known.
  const std::vector<RendezvousEvent>& rendezvous() const;
  std::vector<FrameTransform> known_transforms() const;
  std::vector<std::string> frames_known() const;
  // Per other robot whose data reached this agent: the steps 1..n of its run taken in (raw steps
  // held, or the step of the last map snapshot merged, whichever is later).
  std::map<std::string, std::uint32_t> data_held() const;
  // Peer messages rejected so far: malformed ones and, among them counted apart, those only out of
  // order (stale_messages: older than one already applied from the sender). A snapshot or notice
  // from a peer whose frame is not known yet, as happens in realtime when it overtakes the
  // detections that make the rendezvous, is held until the frame is known (the newest snapshot
  // and kMaxEarlyNotices notices per peer).
  int rejected_messages() const;
  int stale_messages() const { return stale_; }
  // Every transform estimated jointly from both robots' histories (cooperation.joint_transform),
  // in order: the peer, the snapshot's step, the estimate.
  const std::vector<FrameTransform>& joint_estimates() const { return joint_estimates_; }
  // Per peer whose map snapshot arrived: its tracks, each with the own track it was matched to
  // and its kinematics (the newest snapshot's word on a track).
  PeerTrackLinks track_links() const;
  // Appends to estimate's map the peers' landmarks streamed with their raw measurements that it
  // does not hold (cooperation.stream_landmarks; StreamedLandmarks): for the estimate published.
  void CompleteMap(filters::FilterEstimate* estimate) const;
  // The raw measurements held, the own and the peers' (cooperation.share_factors).
  const FactorExchange& exchange() const { return exchange_; }
  // The bytes the streamed landmarks' bookkeeping holds (StreamedLandmarks::Bytes).
  std::size_t streamed_bytes() const { return streamed_.Bytes(); }
  // Landmark-moved notices accepted so far (the ELA filter will use them).
  int moved_notices() const { return moved_notices_; }
  // Mutual detections used to correct the own pose (cooperative localization).
  int cooperative_updates() const { return cooperative_updates_; }

  // Writes or reads back what changes as the agent runs: per peer its transform, detections and
  // encounter, the rendezvous, the counters, the own history (what the options fix is not
  // written).
  void Io(common::Archive& ar) {
    ar(peers_, rendezvous_, last_step_, any_step_, rejected_, stale_, moved_notices_, cooperative_updates_,
       joint_estimates_, first_pose_, history_, history_usable_);
    exchange_.Io(ar);
    streamed_.Io(ar);
  }

 private:
  // The own detection of a peer at a step, with the own pose estimate of that step.
  struct OwnDetection {
    double range_m = 0.0;
    double bearing_rad = 0.0;
    common::Pose2 pose;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();

    void Io(common::Archive& ar) { ar(range_m, bearing_rad, pose, covariance); }
  };
  static constexpr std::uint32_t kEncounterRefineSteps = 10;
  static constexpr std::size_t kMaxEarlyNotices = 16;  // held per peer before its frame is known

  // Everything known about one peer.
  struct PeerState {
    std::optional<TransformEstimate> transform;  // T(G_self <- G_peer)
    bool met = false;                            // from own mutual detections (else chained)
    // The last mutual detection lay beyond the transform gate of the one held: one of the two
    // robots is off in its own frame, and a snapshot from the peer is not merged meanwhile.
    bool last_detection_outlier = false;
    std::uint32_t transform_step = 0;  // when last estimated
    // Detections not yet paired into a mutual detection, by step (bounded by the window).
    std::map<std::uint32_t, OwnDetection> own_detections;
    std::map<std::uint32_t, RelativeMeasurement> peer_measurements;
    // The current encounter: a run of mutual detections at most window_steps apart.
    bool in_encounter = false;
    std::uint32_t encounter_first = 0, encounter_last = 0;
    int encounter_pairs = 0;
    int event_index = -1;  // into rendezvous_ while the encounter refines its event
    std::optional<std::uint32_t> last_rendezvous_step;
    bool snapshot_due = false;    // the map and the transforms go to the peer after this step
    bool transforms_due = false;  // the transforms only (an encounter that is not a rendezvous)
    // The last step applied per message kind (older ones are stale).
    std::optional<std::uint32_t> last_measurement_step, last_snapshot_step, last_notice_step;
    std::map<int, TrackLink> tracks;  // its tracks in its snapshots (LinkTracks)
    // Come before its frame is known (in realtime a snapshot can overtake the detections that
    // make the rendezvous): held until it is, the newest snapshot and the newest notices.
    std::optional<MapSnapshot> early_snapshot;
    std::vector<LandmarkMovedNotice> early_notices;

    void Io(common::Archive& ar) {
      ar(transform, met, last_detection_outlier, transform_step, own_detections, peer_measurements, in_encounter,
         encounter_first, encounter_last, encounter_pairs, event_index, last_rendezvous_step, snapshot_due,
         transforms_due, last_measurement_step, last_snapshot_step, last_notice_step, tracks, early_snapshot,
         early_notices);
    }
  };

  // Checks the parts every message shares: from a known other robot, to this one, not from a
  // step after the current one.
  bool HeaderValid(const PeerHeader& h) const;
  bool MeasurementValid(const RelativeMeasurement& m) const;
  bool SnapshotValid(const MapSnapshot& m) const;
  bool HistoryValid(const MapSnapshot& m) const;
  // Pairs own detections and peer measurements into mutual detections and applies them.
  void PairMutualDetections(const std::string& peer, filters::SlamFilter* filter);
  void ApplyMutualDetection(const std::string& peer, std::uint32_t own_step, const OwnDetection& own,
                            const RelativeMeasurement& theirs, filters::SlamFilter* filter);
  void ApplySnapshot(const MapSnapshot& m, filters::SlamFilter* filter);
  // A snapshot or notice from a peer whose frame is known: stale if older than the last of its
  // kind applied from that peer, else applied.
  void ApplySnapshotInOrder(const MapSnapshot& m, filters::SlamFilter* filter);
  void ApplyNoticeInOrder(const LandmarkMovedNotice& n, filters::SlamFilter* filter);
  // The messages held from peers whose frames are now known, applied in order.
  void ApplyEarlyMessages(filters::SlamFilter* filter);
  // Hold a message from a peer whose frame is not known yet: the newest snapshot, and the
  // kMaxEarlyNotices newest notices.
  void HoldEarlySnapshot(PeerState* peer, const MapSnapshot& m);
  void HoldEarlyNotice(PeerState* peer, const LandmarkMovedNotice& n);
  // Whether a message of `step` may be applied after the last of its kind (*last_step, then set
  // to step); an older one is counted stale.
  bool InOrder(std::optional<std::uint32_t>* last_step, std::uint32_t step);
  // The landmarks both maps hold: the own and the snapshot's (at the same step; those that came
  // from the other side by provenance left out), matched through the held transform.
  struct CommonLandmarks {
    std::vector<filters::MapLandmark> mine, theirs;
    std::vector<int> match;  // per theirs: the index into mine, or -1
  };
  CommonLandmarks MatchSnapshot(const MapSnapshot& m, const filters::FilterEstimate& own,
                                const TransformEstimate& held) const;
  // Keeps the sender's tracks in `common` with their kinematics and the own tracks they matched.
  void LinkTracks(const CommonLandmarks& common, PeerState* sender) const;
  // Refines the transform to the snapshot's sender by the landmarks both maps hold (aligned by
  // AlignLandmarks with the held one as prior).
  void AlignWithSnapshot(const MapSnapshot& m, const CommonLandmarks& common, PeerState* sender);
  // The transform to the snapshot's sender from both robots' histories (the joint MAP estimate
  // of both paths and the landmarks, BatchSmoother), or nothing when either history is missing
  // or the estimate fails or disagrees with the held one beyond transform_gate_probability.
  std::optional<TransformEstimate> JointTransform(const MapSnapshot& m, const filters::FilterEstimate& own,
                                                  const CommonLandmarks& common, const TransformEstimate& held) const;
  // Whether the own history can take part in a joint estimate: joint_transform on, the history
  // whole, and landmark kinematics it models (static or known candidates, not a constant turn rate).
  bool JointPossible() const {
    return options_.cooperation.joint_transform && history_usable_ &&
           options_.filter.landmark_kinematics != LandmarkKinematics::kConstantTurnRate;
  }
  // The kinematics the joint estimate gives a mapped landmark: static, or the known candidate
  // nearest to its (v, w); nothing for a landmark whose heading is not known yet or that is
  // tracked with a constant turn rate.
  std::optional<smoother::BatchSmoother::Kinematics> JointKinematics(const filters::MapLandmark& l) const;
  // Keeps the step in the own history (while it is usable for the joint estimate).
  void Record(const common::SensorStep& step, const filters::FilterEstimate& estimate);
  // The own step into the exchange (with the estimates of the landmarks it read) and the misses
  // of the streamed landmarks it shows.
  void Share(const common::SensorStep& step, const filters::FilterEstimate& estimate,
             const std::optional<common::SensorStep>& labelled);
  // Whether an estimate made at step still refines the peer's current rendezvous event.
  bool Refining(const PeerState& peer, std::uint32_t step) const;
  // Holds t as the transform to peer, estimated at step (and as the event's, while refining).
  void HoldTransform(PeerState* peer, const TransformEstimate& t, std::uint32_t step);
  // The snapshot for peer: the transforms held (but the peer's own), and the map if with_map.
  MapSnapshot MakeSnapshot(const std::string& peer, const filters::FilterEstimate& estimate, bool with_map) const;
  void Reject() { ++rejected_; }
  void RejectStale() {
    ++rejected_;
    ++stale_;
  }

  AgentOptions options_;
  std::string robot_id_;
  int self_index_ = -1;  // in the team (the provenance of the own landmarks)
  double var_range_ = 0.0, var_bearing_ = 0.0;
  std::map<std::string, PeerState> peers_;
  std::vector<RendezvousEvent> rendezvous_;
  std::uint32_t last_step_ = 0;  // of the last AfterStep
  bool any_step_ = false;
  int rejected_ = 0;
  int stale_ = 0;
  int moved_notices_ = 0;
  int cooperative_updates_ = 0;
  std::vector<FrameTransform> joint_estimates_;
  // The own history for the joint estimate: every step from step 1, each landmark detection
  // labelled by its track (unlabelled ones left out); usable while no step is missing, every
  // scan came labelled and it is within max_history_steps.
  common::Pose2 first_pose_;
  std::vector<common::SensorStep> history_;
  bool history_usable_ = true;
  FactorExchange exchange_;
  StreamedLandmarks streamed_;
};

}  // namespace mrslam::robot_agent::cooperation
