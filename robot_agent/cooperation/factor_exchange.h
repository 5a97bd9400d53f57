#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "common/archive.h"
#include "common/se2.h"
#include "common/sensor_archive.h"
#include "common/sensor_types.h"
#include "robot_agent/cooperation/peer_messages.h"
#include "robot_agent/filters/slam_filter.h"
#include "robot_agent/options/agent_options.h"

// Raw measurements shared peer to peer (docs/cooperation.md, "Sharing raw measurements"). A
// robot's measurements are its steps: step t's odometry segments and its scan, each landmark
// detection labelled by the robot's own track of it (unlabelled ones left out) and each robot
// detection naming the robot seen; no IMU. A step is known everywhere by (origin robot, step),
// so a step that reaches an agent twice, by two relays, enters once.
namespace mrslam::robot_agent::cooperation {

// One robot's steps as an agent holds them: its first pose in its own frame and its steps
// 1..n without a gap (steps[i] is step i + 1), and the newest estimate of each of its labels at
// a step held.
struct FactorLog {
  common::Pose2 first_pose;
  std::vector<common::SensorStep> steps;
  std::map<std::uint32_t, TrackEstimate> tracks;  // by label
  std::string fed_by;                             // the peer that last sent new steps of it (empty: none, the own log)
  std::uint32_t fed_at = 0;                       // the step of that peer's batch

  std::uint32_t Held() const { return static_cast<std::uint32_t>(steps.size()); }
  void Io(common::Archive& ar) { ar(first_pose, steps, tracks, fed_by, fed_at); }
};

// The step as a measurement to share: its odometry, its robot detections and its landmark
// detections labelled, the stamp kept; nothing when the filter does not label its detections.
// A detection's label is its track in estimate.detection_tracks (the robot's own; the unlabelled
// left out), or with by_identity its identity + 1 when it has one (sensors.lidar.report_identity:
// every robot's labels then name the same landmarks; the raw measurements shared are so).
std::optional<common::SensorStep> LabelledStep(const common::SensorStep& step, const filters::FilterEstimate& estimate,
                                               bool by_identity);

// The estimates of the landmarks the step's labelled detections name (labelled as LabelledStep
// labels them): each confirmed landmark of estimate a detection is associated with, once.
std::vector<TrackEstimate> TrackEstimates(const common::SensorStep& step, const filters::FilterEstimate& estimate,
                                          bool by_identity);

// The step in the precision it is shared in (docs/cooperation.md, "Size and precision"): one stamp
// (the odometry's is the scan's); each time the step's time plus a whole number of microseconds
// (TimeOffsetUs, within +-kMaxTimeOffsetUs); each value rounded to single precision (about 1e-7
// relative, far below any sensor's noise). The own log holds this form, so every agent's graph
// sees the origin's numbers to the bit. Idempotent.
constexpr std::int32_t kMaxTimeOffsetUs = 1'000'000'000;
std::int32_t TimeOffsetUs(double time_s, double step_time_s);
double OffsetTime(double step_time_s, std::int32_t offset_us);
common::SensorStep SharedPrecision(common::SensorStep step);
TrackEstimate SharedPrecision(TrackEstimate t);

// Whether s is a well-formed shared step `step`: that stamp, finite values, a positive range,
// a track label on every landmark detection, a seen robot named on every robot detection, no
// IMU, at most 256 items per kind.
bool SharedStepValid(const common::SensorStep& s, std::uint32_t step);
// Bounds of a landmark estimate shared: its label, its position's coordinates, its covariances'
// entries, its speed and turn rate; and how many labels a log keeps (the newest).
constexpr std::uint32_t kMaxTrackLabel = (1U << 20) - 1;
constexpr double kMaxTrackCoordinateM = 1e6;
constexpr double kMaxTrackVariance = 1e12;
constexpr double kMaxTrackRate = 1e3;
constexpr std::size_t kMaxTracksHeld = 1024;

// Whether t is a well-formed estimate of a run's steps first..last: a label in 1..kMaxTrackLabel,
// a step in the run, finite values within the bounds above, a positive definite position
// covariance, a non-negative heading variance.
bool TrackEstimateValid(const TrackEstimate& t, std::uint32_t first, std::uint32_t last);

// An agent's side of the exchange. Pure; not thread-safe.
//
// Sending: after step k, to every peer its own lidar detected at a step within
// cooperation.exchange_window_steps before k (from rendezvous.enable_from_step on), one batch.
// A session of batches to a peer (steps in a row) starts with a greeting: for kAckLagSteps + 1
// steps, or until the peer's own batch of the session says what it holds, the batch carries no
// steps, as the peer may have had them from others meanwhile. Then it carries the steps that peer
// lacks: of every origin it holds (only its own with relaying off), but
// the peer's own, from what was sent before (taken as on its way), at most
// cooperation.max_batch_steps steps in all, its own origin first; a run carries the origin's track
// estimates made at its steps (TrackEstimate). Another origin's steps go only
// once the peer lacks more than kRelayLagSteps of them: a peer that lacks fewer most likely gets
// them from the origin itself or from another relay, and sending them too would double them. What does not fit goes at
// the next step of the window or of the next one. Nor does another origin's step go to a peer that says another robot
// sent it new steps of that origin within the last kAckLagSteps + 1 steps (it is being fed them). A batch the peer sent
// at step h tells what it holds after the batches sent to it up to step h - kAckLagSteps: when it holds less of an
// origin than those sent (a batch was lost), the sending starts again from what it holds. A robot seen by one that
// does not see it (a narrow field of view) never sends to it; so, with relaying on, a batch also passes on what the
// sender last heard other robots hold (their newest batch's holdings, to whichever peer, with its step), each
// robot's at most every kHeardSteps steps and only when newer than passed on before: the recipient takes it as if
// it had heard it itself at that step, and sends such a robot only what it lacks by the freshest word of it.
// Receiving: a batch is rejected whole (and counted) unless it is well formed and within its
// window: opened_by_step no later than the batch's step and at most exchange_window_steps before
// it, and the sender's step opened_by_step (held, in a run or the batch's opening) detects this
// robot; no run of this robot's own steps, none of another origin with relaying off. A batch
// whose opening step cannot be found (the recipient lost the batch that carried it) is left out
// as a gap, not rejected. An accepted batch's runs extend the logs: the steps already held are
// skipped, a run that starts beyond the first step missing is left out (counted as a gap: the
// sender will send from the count this agent says it holds). Holdings, the sender's and those passed on, are well
// formed (team origins, none twice, counts and feeding steps no later than the report's step plus
// exchange_window_steps; passed on: of team robots but the sender and this agent, none twice, of a step no later
// than the batch's) or the batch is rejected; those passed on replace what this agent last heard of that robot when
// newer. What is passed on goes only in a batch that is sent.
class FactorExchange {
 public:
  static constexpr std::uint32_t kAckLagSteps = 2;
  static constexpr std::uint32_t kRelayLagSteps = 10;
  static constexpr std::uint32_t kTrackRefreshSteps = 10;
  static constexpr std::uint32_t kHeardSteps = 10;

  explicit FactorExchange(const AgentOptions& options);

  // The own step k (LabelledStep) goes into the own log, in SharedPrecision, with the estimates
  // of the landmarks it read (TrackEstimates; a label's estimate is renewed when it is a mover's
  // or kTrackRefreshSteps old; one that is not TrackEstimateValid in its shared precision is left
  // out); its robot detections open the window to those peers. A step that
  // does not follow the last one ends the own log's growth (a gap cannot be shared).
  void RecordOwn(const common::SensorStep& labelled, const std::vector<TrackEstimate>& tracks = {});
  // The batches to send after step k (header: sender, recipient, k, time_s; sequence 0).
  std::vector<FactorBatch> Outgoing(std::uint32_t k, double time_s);
  // Validates and applies one batch; false when it is rejected.
  bool Receive(const FactorBatch& batch);

  // Every origin's log held, the own included (by robot id).
  const std::map<std::string, FactorLog>& logs() const { return logs_; }
  std::uint32_t Held(const std::string& origin) const;
  // The bytes of the steps held, every origin's (sizeof(element) * size() over their containers,
  // as SlamFilter::EstimatorBytes counts). Logs only grow at their ends, so each step is counted
  // once, when first seen (a log that shrank, restored, is counted again).
  std::size_t HeldBytes() const;
  int gaps() const { return gaps_; }
  // Steps taken in from peers (each once), steps that came again (already held), steps sent.
  std::uint64_t steps_received() const { return steps_received_; }
  std::uint64_t steps_again() const { return steps_again_; }
  std::uint64_t steps_sent() const { return steps_sent_; }

  void Io(common::Archive& ar) {
    ar(logs_, own_growing_, detected_at_, peer_holdings_, holdings_step_, sends_, session_start_, last_batch_,
       heard_passed_, gaps_, steps_received_, steps_again_, steps_sent_);
    if (ar.loading()) counted_.clear();
  }

 private:
  bool BatchValid(const FactorBatch& b) const;
  // Holdings reported at `step`: of team origins, none twice, a feeder of the team if any, counts and
  // feeding steps no later than step + exchange_window_steps.
  bool HoldingsValid(const std::vector<FactorHolding>& holdings, std::uint32_t step) const;
  // The holdings passed on.
  bool HeardValid(const FactorBatch& b) const;
  // What robot said it holds in its batch of its step `step`, unless older than what was heard of it.
  void Hear(const std::string& robot, std::uint32_t step, const std::vector<FactorHolding>& holdings);
  // What this agent heard other robots hold, newer than passed on to peer before; each robot's at most every
  // kHeardSteps steps.
  void AddHeard(const std::string& peer, std::uint32_t k, FactorBatch* batch);
  // A run's estimates: at most kMaxItems, each TrackEstimateValid, of a label a reading of its
  // step names, no label twice.
  static bool TracksValid(const FactorRun& run);
  // The sender's step opened_by_step: held, in the batch's runs or its opening; nullptr if none.
  const common::SensorStep* Opening(const FactorBatch& b) const;
  void Apply(const FactorRun& run, const PeerHeader& from);
  // Whether peer is being fed origin's steps by a robot other than this one (as of step k).
  bool FedByAnother(const std::string& peer, const std::string& origin, std::uint32_t k);
  // The origins to send, in order: the own, then the others in team order.
  std::vector<std::string> SendOrder() const;
  std::optional<FactorBatch> BatchFor(const std::string& peer, std::uint32_t k, double time_s);
  // The runs of the steps peer lacks, at most max_batch_steps steps in all.
  void AddRuns(const std::string& peer, std::uint32_t k, FactorBatch* batch);
  // The first step of origin to send peer: past what it holds or was sent, or from what it
  // holds again when its newest batch shows a loss.
  std::uint32_t SendFrom(const std::string& peer, const std::string& origin);

  AgentOptions options_;
  std::string self_;
  std::map<std::string, FactorLog> logs_;
  struct Counted {
    std::size_t steps = 0, bytes = 0;
  };
  mutable std::map<std::string, Counted> counted_;  // HeldBytes's count so far, per origin
  bool own_growing_ = true;
  std::map<std::string, std::uint32_t> detected_at_;  // per peer: the last own step detecting it
  // Per robot and origin: the count it last said it holds (in its newest batch heard of, directly or passed on,
  // sent at holdings_step_), and per peer what was sent to it (by the step sent at: steps 1..n sent).
  std::map<std::string, std::map<std::string, FactorHolding>> peer_holdings_;
  std::map<std::string, std::uint32_t> holdings_step_;
  std::map<std::string, std::map<std::string, std::map<std::uint32_t, std::uint32_t>>> sends_;
  // Per peer: the step of the first batch of the current session, and of the last batch.
  std::map<std::string, std::uint32_t> session_start_, last_batch_;
  // Per peer and robot: the step of the robot's holdings last passed on to the peer, and the own step it was done at.
  struct Passed {
    std::uint32_t step = 0, at = 0;
    void Io(common::Archive& ar) { ar(step, at); }
  };
  std::map<std::string, std::map<std::string, Passed>> heard_passed_;
  int gaps_ = 0;
  std::uint64_t steps_received_ = 0, steps_again_ = 0, steps_sent_ = 0;
};

}  // namespace mrslam::robot_agent::cooperation
