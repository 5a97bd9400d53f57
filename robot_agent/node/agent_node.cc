#include "robot_agent/node/agent_node.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include <spdlog/spdlog.h>

#include "common/archive.h"
#include "common/cpu_clock.h"
#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "common/snapshot_file.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/cooperation/cooperation.h"
#include "robot_agent/cooperation/held_factors.h"
#include "robot_agent/cooperation/joint_estimate.h"
#include "robot_agent/cooperation/joint_tracker.h"
#include "robot_agent/cooperation/sample_intake.h"
#include "robot_agent/cooperation/sample_validation.h"
#include "robot_agent/node/msg_conversion.h"
#include "robot_agent/node/peer_endpoints.h"
#include "robot_agent/node/peer_writer_pool.h"

namespace mrslam::robot_agent {

namespace {
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// A sensor step with its DDS hop: this agent's reception less the writer's write, microseconds
// (0: unknown).
struct ReceivedSensorStep {
  common::SensorStep step;
  double hop_us = 0.0;
};
}  // namespace

struct AgentNode::Impl {
  AgentOptions agent;
  AgentNodeOptions options;
  std::unique_ptr<filters::SlamFilter> filter;
  dds::Participant participant;
  dds::Notifier notifier;
  dds::Reader<msg::SensorStepPubSubType> sensor_reader;
  dds::Reader<msg::StepClockPubSubType> clock_reader;
  dds::Writer<msg::EstimatePubSubType> estimate_writer;
  dds::Writer<msg::StepAckPubSubType> ack_writer;
  dds::Writer<msg::FinalTrajectoryPubSubType> final_writer;
  std::map<std::uint32_t, double> step_times;  // every step's time, for the final trajectory
  // Readers of every peer's topics into this agent and, when first needed, writers into the peers'
  // (in realtime opened in the background: the messages to a peer wait in `held` until they are).
  std::map<std::string, std::unique_ptr<PeerReaders>> from_peers;
  PeerWriterPool peers;
  std::map<std::string, PeerMessages> held;
  cooperation::Cooperation cooperation;
  cooperation::JointTracker joint_tracker;
  // Peer messages received, by the sender's step: applied at the start of the next step.
  std::map<std::uint32_t, cooperation::PeerInbox> inbox;
  // (sender, step) -> the sequence numbers received, for the steps not yet applied.
  std::map<std::pair<std::string, std::uint32_t>, std::set<std::uint32_t>> received;
  // The highest sequence number of the messages of each sender's steps already applied.
  std::map<std::string, std::uint32_t> applied_sequence;
  std::map<std::string, std::uint32_t> sent_sequence;
  // Serialized bytes of the peer messages sent to and taken in from each peer so far.
  std::map<std::string, std::uint64_t> bytes_sent_to, bytes_received_from;
  AgentCounters counters;
  std::uint32_t next_step = 1;
  std::uint32_t restored_step = 0;    // the step of the snapshot restored at the start (0: none)
  std::size_t rendezvous_logged = 0;  // rendezvous() entries logged so far
  // Sensor steps buffered by step until the step is complete, taken only from the simulator.
  cooperation::StepSlots<ReceivedSensorStep> sensors;
  std::map<std::uint32_t, msg::StepClock> clock;
  cooperation::SimulatorBinding simulator;

  Impl(const AgentOptions& a, const AgentNodeOptions& o, std::unique_ptr<filters::SlamFilter> f)
      : agent(a),
        options(o),
        filter(std::move(f)),
        participant(
            {o.domain, "robot_agent/" + a.robot_id, o.shared_memory, o.security_dir, a.robot_id, o.history_steps}),
        sensor_reader(participant, dds::SensorTopic(a.robot_id), &notifier),
        clock_reader(participant, dds::kClockTopic, &notifier),
        // In realtime the estimates are acknowledged once a second (participant.h).
        estimate_writer(participant, dds::EstimateTopic(a.robot_id), dds::History::kRecent,
                        o.lockstep ? dds::Acknowledgment::kPrompt : dds::Acknowledgment::kPerSecond),
        ack_writer(participant, dds::AckTopic(a.robot_id)),
        final_writer(participant, dds::FinalTrajectoryTopic(a.robot_id), dds::History::kWhole),
        peers(participant, a.robot_id, a.cooperation.share_factors, !o.lockstep),
        cooperation(a),
        joint_tracker(a),
        sensors(o.horizon_steps) {
    for (const auto& peer : a.team) {
      if (peer != a.robot_id)
        from_peers[peer] =
            std::make_unique<PeerReaders>(participant, a.robot_id, peer, &notifier, a.cooperation.share_factors);
    }
  }

  void Reject(cooperation::Rejection kind, const std::string& why, std::uint32_t n = 1) {
    counters.rejected.Add(kind, n);
    spdlog::warn("rejected ({}): {} (rejected so far: {})", cooperation::RejectionName(kind), why,
                 counters.rejected.Describe());
  }

  // Whether a sample or clock of `step` is one the restored snapshot already holds: a replay from
  // the DDS history, dropped without a count (without a snapshot, an old step is stale).
  bool Replayed(std::uint32_t step) const { return restored_step > 0 && step <= restored_step; }

  // Buffers a sensor step of a future or current step, or rejects it.
  void Buffer(ReceivedSensorStep in, const common::WriterId& writer) {
    common::SensorStep& sample = in.step;
    const common::Stamp& stamp = sample.odometry.stamp;
    const std::uint32_t step = stamp.step;
    if (const auto problem = cooperation::StampProblem(stamp, agent.robot_id); !problem.empty()) {
      Reject(cooperation::Rejection::kMalformed, "sensor step: " + problem);
      return;
    }
    if (Replayed(step)) return;
    if (const int bad = cooperation::SanitizeSensorStep(&sample); bad > 0) {
      Reject(cooperation::Rejection::kMalformed, fmt::format("{} malformed sensor item(s) of step {}", bad, step),
             static_cast<std::uint32_t>(bad));
    }
    if (const auto kind = sensors.Offer(step, next_step, writer, std::move(in))) {
      Reject(*kind, fmt::format("sensor step {} (the agent is at step {})", step, next_step));
    }
  }

  void Drain() {
    common::WriterId writer{};
    msg::SensorStep m;
    dds::SampleTimes times;
    while (sensor_reader.TryTake(&m, &writer, &times)) Buffer({dds::FromMsg(m), times.HopUs()}, writer);
    msg::StepClock c;
    while (clock_reader.TryTake(&c, &writer)) AcceptClock(c, writer);
    for (auto& [peer, from] : from_peers) DrainPeer(peer, from.get());
  }

  // Takes what one peer sent on its own topics into this agent.
  void DrainPeer(const std::string& peer, PeerReaders* from) {
    msg::RelativeMeasurement r;
    while (from->relative.TryTake(&r)) {
      bytes_received_from[peer] += msg::RelativeMeasurement::getCdrSerializedSize(r);
      AcceptPeer(peer, FromMsg(r), &cooperation::PeerInbox::measurements);
    }
    msg::MapSnapshot ms;
    while (from->map.TryTake(&ms)) {
      bytes_received_from[peer] += msg::MapSnapshot::getCdrSerializedSize(ms);
      AcceptPeer(peer, FromMsg(ms), &cooperation::PeerInbox::maps);
    }
    msg::LandmarkMovedNotice n;
    while (from->moved.TryTake(&n)) {
      bytes_received_from[peer] += msg::LandmarkMovedNotice::getCdrSerializedSize(n);
      AcceptPeer(peer, FromMsg(n), &cooperation::PeerInbox::moved);
    }
    msg::FactorBatch f;
    while (from->factors && from->factors->TryTake(&f)) {
      bytes_received_from[peer] += msg::FactorBatch::getCdrSerializedSize(f);
      AcceptPeer(peer, FromMsg(f), &cooperation::PeerInbox::factors);
    }
  }

  // Keeps a step clock from the simulator (the first participant to deliver one), or rejects it.
  void AcceptClock(const msg::StepClock& c, const common::WriterId& writer) {
    const std::uint32_t step = c.stamp().step();
    using cooperation::Rejection;
    if (const auto kind = simulator.OfferClock(writer)) {
      Reject(*kind, fmt::format("a step clock of step {} from a second participant", step));
    } else if (Replayed(step)) {
      return;
    } else if (step < next_step) {
      Reject(Rejection::kStale, fmt::format("the step clock of step {} (the agent is at step {})", step, next_step));
    } else if (step - next_step > options.horizon_steps) {
      Reject(Rejection::kBeyondHorizon,
             fmt::format("a step clock of step {} (the agent is at step {})", step, next_step));
    } else if (!clock.emplace(step, c).second) {
      Reject(Rejection::kDuplicate, fmt::format("a second step clock of step {}", step));
    }
  }

  // Buffers a peer message that came on topic_sender's topic (a peer of the team) for the start
  // of the step after the one it was sent in, or rejects it (a sender other than the topic's, not
  // for us, a step already past or beyond the horizon).
  template <typename T>
  void AcceptPeer(const std::string& topic_sender, T message, std::vector<T> cooperation::PeerInbox::*list) {
    const auto& h = message.header;
    using cooperation::Rejection;
    if (h.sender != topic_sender) {
      Reject(Rejection::kMalformed, "peer message from '" + h.sender + "' on " + topic_sender + "'s topic");
      return;
    }
    if (h.recipient != agent.robot_id) {
      Reject(Rejection::kMalformed, "peer message for '" + h.recipient + "' in " + agent.robot_id + "'s inbox");
      return;
    }
    if (IsReplay(h)) {
      spdlog::debug("peer message {} of step {} from {} received again (a restarted peer replays): ignored", h.sequence,
                    h.step, h.sender);
      return;
    }
    if (h.step > next_step && h.step - next_step > options.horizon_steps) {
      Reject(Rejection::kBeyondHorizon, "peer message of step " + std::to_string(h.step) + " from " + h.sender);
      return;
    }
    // Applied at the start of the step after its own (the messages of step k at step k + 1).
    std::uint32_t step = h.step;
    if (h.step + 1 < next_step) {
      // Its step is past: stale in lockstep (the agent waited for what the clock announced);
      // in realtime late, applied at the next step (the cooperation still rejects one older
      // than a message of the same kind it applied from that sender).
      if (options.lockstep) {
        Reject(Rejection::kStale, "peer message of step " + std::to_string(h.step) + " from " + h.sender);
        return;
      }
      ++counters.peer_messages_late;
      step = next_step - 1;
    }
    received[{h.sender, step}].insert(h.sequence);
    (inbox[step].*list).push_back(std::move(message));
  }

  // A message this agent already has: a peer that was restarted sends again, with the same
  // sequence numbers, what it sent before it died (docs/faults.md). Sequence numbers grow with the
  // sender's steps, so one at or below those of the steps applied is a replay.
  bool IsReplay(const cooperation::PeerHeader& h) const {
    if (const auto a = applied_sequence.find(h.sender); a != applied_sequence.end() && h.sequence <= a->second)
      return true;
    const auto r = received.find({h.sender, h.step});
    return r != received.end() && r->second.count(h.sequence) > 0;
  }

  // How many peer messages to this agent the clock of step k announces from each sender (those
  // sent during step k-1).
  std::map<std::string, std::uint32_t> Announced(const msg::StepClock& c) const {
    std::map<std::string, std::uint32_t> out;
    for (const auto& d : c.peer_deliveries()) {
      if (d.recipient_id() == agent.robot_id) out[d.sender_id()] += d.count();
    }
    return out;
  }

  // True when every peer message the clock of step k announces is here.
  bool PeerMessagesComplete(const msg::StepClock& c) const {
    for (const auto& [sender, count] : Announced(c)) {
      const auto it = received.find({sender, c.stamp().step() - 1});
      if ((it == received.end() ? 0U : it->second.size()) < count) return false;
    }
    return true;
  }

  // In lockstep, peer messages of step k-1 beyond those the clock of step k announces were
  // written by someone other than the peers the simulator counted: contested, and none of that
  // sender's messages of that step is used (which is genuine cannot be told). Forgets the counts
  // of step k-1.
  void CheckPeerCounts(const msg::StepClock& c) {
    const std::uint32_t sent_step = c.stamp().step() - 1;
    const auto announced = Announced(c);
    for (auto it = received.begin(); it != received.end();) {
      if (it->first.second != sent_step) {
        ++it;
        continue;
      }
      const auto a = announced.find(it->first.first);
      const std::uint32_t expected = a == announced.end() ? 0U : a->second;
      const auto count = static_cast<std::uint32_t>(it->second.size());
      if (options.lockstep && count > expected) {
        Reject(cooperation::Rejection::kContested,
               fmt::format("{} peer message(s) of step {} from {} where the simulator counted {}; none is used", count,
                           sent_step, it->first.first, expected),
               count - expected);
        DropPeerMessages(sent_step, it->first.first);
      }
      if (!it->second.empty()) {
        auto& applied = applied_sequence[it->first.first];
        applied = std::max(applied, *it->second.rbegin());
      }
      it = received.erase(it);
    }
  }

  void DropPeerMessages(std::uint32_t step, const std::string& sender) {
    const auto in = inbox.find(step);
    if (in == inbox.end()) return;
    const auto from_sender = [&](const auto& m) { return m.header.sender == sender; };
    auto drop = [&](auto* list) { list->erase(std::remove_if(list->begin(), list->end(), from_sender), list->end()); };
    drop(&in->second.measurements);
    drop(&in->second.maps);
    drop(&in->second.moved);
    drop(&in->second.factors);
  }

  // Converts and stamps a step's peer messages and counts their bytes as sent (they are
  // written right after the step's estimate, which reports the count).
  PeerMessages Prepare(cooperation::PeerOutbox outbox) {
    PeerMessages out;
    auto stamp = [&](auto* m) -> const auto& {
      m->header.sequence = ++sent_sequence[m->header.recipient];
      return *m;
    };
    auto count = [&](const auto& message) {
      bytes_sent_to[message.recipient_id()] += std::decay_t<decltype(message)>::getCdrSerializedSize(message);
    };
    for (auto& m : outbox.measurements) count(out.relative.emplace_back(ToMsg(stamp(&m))));
    for (auto& m : outbox.maps) count(out.maps.emplace_back(ToMsg(stamp(&m))));
    for (auto& m : outbox.moved) count(out.moved.emplace_back(ToMsg(stamp(&m))));
    for (auto& m : outbox.factors) count(out.factors.emplace_back(ToMsg(stamp(&m))));
    return out;
  }

  // Writes a step's peer messages; returns the number of messages per recipient. A message to a
  // peer whose writers are not open yet waits in `held`, after those held before it, and goes
  // out at a later step once they are.
  std::map<std::string, std::uint32_t> Send(PeerMessages messages) {
    std::map<std::string, std::uint32_t> counts;
    PeerMessages out;
    for (auto& [peer, waiting] : held) Append(std::move(waiting), &out);
    held.clear();
    Append(std::move(messages), &out);
    // Writes message on the writers' member `writer`, or holds it in the peer's member `waiting`.
    auto send = [&](auto PeerWriters::*writer, auto& message, auto PeerMessages::*waiting) {
      const std::string& peer = message.recipient_id();
      ++counts[peer];
      PeerWriters* w = held.count(peer) > 0 ? nullptr : peers.Get(peer);
      if (w == nullptr) {
        (held[peer].*waiting).push_back(std::move(message));
        return false;
      }
      if (!Deref(w->*writer).Write(message)) throw AgentError("DDS refused a peer message to " + peer);
      return true;
    };
    for (auto& m : out.relative) send(&PeerWriters::relative, m, &PeerMessages::relative);
    for (auto& m : out.maps) {
      const std::size_t landmarks = m.landmarks().size(), history = m.history().size();
      const std::string peer = m.recipient_id();
      if (send(&PeerWriters::map, m, &PeerMessages::maps)) {
        spdlog::info("sent a map snapshot of {} landmarks and a history of {} steps to {}", landmarks, history, peer);
      }
    }
    for (auto& m : out.moved) send(&PeerWriters::moved, m, &PeerMessages::moved);
    for (auto& m : out.factors) send(&PeerWriters::factors, m, &PeerMessages::factors);
    return counts;
  }

  static void Append(PeerMessages from, PeerMessages* to) {
    auto move = [](auto* a, auto* b) {
      b->insert(b->end(), std::make_move_iterator(a->begin()), std::make_move_iterator(a->end()));
    };
    move(&from.relative, &to->relative);
    move(&from.maps, &to->maps);
    move(&from.moved, &to->moved);
    move(&from.factors, &to->factors);
  }
  template <typename W>
  static W& Deref(W& w) {
    return w;
  }
  template <typename W>
  static W& Deref(std::optional<W>& w) {
    return *w;
  }

  void Acknowledge(std::uint32_t step, double time_s, const std::map<std::string, std::uint32_t>& sent = {}) {
    msg::StepAck ack;
    ack.stamp(dds::ToMsg(common::Stamp{agent.robot_id, step, time_s}));
    for (const auto& [peer, count] : sent) {
      msg::PeerCount pc;
      pc.peer_id(peer);
      pc.count(count);
      ack.peer_messages_sent().push_back(pc);
    }
    ack.rejected_samples(counters.rejected.Total());
    if (!ack_writer.Write(ack))
      throw AgentError("DDS refused to publish the acknowledgement of step " + std::to_string(step));
  }

  static void SortBySender(cooperation::PeerInbox* in) {
    auto order = [](const auto& a, const auto& b) {
      return std::tie(a.header.sender, a.header.sequence) < std::tie(b.header.sender, b.header.sequence);
    };
    std::sort(in->measurements.begin(), in->measurements.end(), order);
    std::sort(in->maps.begin(), in->maps.end(), order);
    std::sort(in->moved.begin(), in->moved.end(), order);
    std::sort(in->factors.begin(), in->factors.end(), order);
  }

  // Logs each rendezvous once its transform is settled (the encounter's refinement steps are
  // over) or the run ends.
  void LogRendezvous(std::uint32_t step, bool last) {
    const auto& events = cooperation.rendezvous();
    for (; rendezvous_logged < events.size(); ++rendezvous_logged) {
      const cooperation::RendezvousEvent& e = events[rendezvous_logged];
      if (!last && cooperation::Cooperation::WithinRefinement(e.step, step)) return;
      const Eigen::Vector3d sd = e.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      spdlog::info(
          "rendezvous with {} at step {}: T({} <- {}) = ({:.3f}, {:.3f}, {:.4f} rad), sd ({:.3f} m, {:.3f} m, "
          "{:.4f} rad)",
          e.peer, e.step, agent.robot_id, e.peer, e.t_self_peer.x, e.t_self_peer.y, e.t_self_peer.heading, sd(0), sd(1),
          sd(2));
    }
  }

  // At the end of the run: publishes the estimator's final trajectory, if it has one; returns the
  // number of chunks.
  std::uint32_t PublishFinalTrajectory(std::uint32_t k, double time_s) {
    const auto path = FinalPath(k);
    if (path.empty()) return 0;
    const auto chunks = FinalTrajectoryChunks(path, step_times, {agent.robot_id, k, time_s});
    for (const auto& chunk : chunks) {
      if (!final_writer.Write(chunk)) throw AgentError("DDS refused to publish the final trajectory");
    }
    spdlog::info("final trajectory: {} poses in {} chunk(s)", path.size(), chunks.size());
    return static_cast<std::uint32_t>(chunks.size());
  }

  // With sharing: the joint estimate solved again when due, and logged (among moving landmarks,
  // where it is solved every step, the first solve only).
  void TrackJoint(std::uint32_t k, const filters::FilterEstimate& estimate) {
    const int before = joint_tracker.solves();
    const auto& x = cooperation.exchange();
    const bool among_movers = cooperation::JointAmongMovers(agent);
    if (among_movers) {
      joint_tracker.AfterStep(k, estimate, x.logs(), x.steps_received(), cooperation.track_links(),
                              cooperation.known_transforms());
    } else {
      joint_tracker.AfterStep(k, estimate, x.logs(), x.steps_received());
    }
    if (joint_tracker.solves() == before || (before > 0 && among_movers)) return;
    const common::Pose2& c = joint_tracker.correction();
    spdlog::info("joint estimate at step {}: the own estimate moved by ({:.3f}, {:.3f}, {:.4f} rad)", k, c.x, c.y,
                 c.heading);
  }

  // The final trajectory: with the raw measurements shared, the own ones held to step k and the
  // landmarks' kinematics modelled (static or known candidates), the own path of the joint
  // estimate over everything held, when it reaches step k; else the estimator's.
  std::vector<std::pair<int, common::Pose2>> FinalPath(std::uint32_t k) {
    const auto& x = cooperation.exchange();
    if (!agent.cooperation.share_factors || x.Held(agent.robot_id) < k) return filter->FinalTrajectory();
    if (!cooperation::JointTracker::Enabled(agent)) {
      spdlog::info("final trajectory: the estimator's, as the joint estimate has no model of its landmarks' motion");
      return filter->FinalTrajectory();
    }
    const auto joint = joint_tracker.Final(x.logs());
    if (joint.path.empty() || joint.path.back().first != static_cast<int>(k)) {
      spdlog::info("final trajectory: the estimator's, as the joint estimate does not reach step {}", k);
      return filter->FinalTrajectory();
    }
    for (const auto& f : joint.frames) {
      const Eigen::Vector3d sd = f.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      spdlog::info("joint estimate: T({} <- {}) = ({:.3f}, {:.3f}, {:.4f} rad), sd ({:.3f} m, {:.3f} m, {:.4f} rad)",
                   agent.robot_id, f.robot, f.t_self_robot.x, f.t_self_robot.y, f.t_self_robot.heading, sd(0), sd(1),
                   sd(2));
    }
    spdlog::info("joint estimate over {} robots' raw measurements ({} not linked): {} readings, {} left out",
                 joint.frames.size() + 1, joint.not_placed.size(), joint.readings, joint.outliers);
    return joint.path;
  }

  // At the end of the run: lets the evaluator and the simulator receive the final estimate and
  // ack, and the peers every peer message (a peer still waits for those of the last steps; a
  // writer deleted before a lost sample is resent would leave it waiting for ever). At most 10 s
  // in all.
  void Flush() {
    const auto deadline = Clock::now() + milliseconds(10000);
    const auto left = [&] {
      return std::max(milliseconds(0), std::chrono::duration_cast<milliseconds>(deadline - Clock::now()));
    };
    estimate_writer.WaitForAcknowledgments(left());
    final_writer.WaitForAcknowledgments(left());
    ack_writer.WaitForAcknowledgments(left());
    if (!held.empty()) {
      peers.WaitAllOpen(deadline);
      Send({});
    }
    for (auto& [peer, w] : peers.Open()) {
      w->relative.WaitForAcknowledgments(left());
      w->map.WaitForAcknowledgments(left());
      w->moved.WaitForAcknowledgments(left());
      if (w->factors) w->factors->WaitForAcknowledgments(left());
    }
  }

  // The agent's state: the node's bookkeeping of steps and peer messages (those received and not
  // applied yet included), the cooperation's and the filter's.
  void Io(common::Archive& ar) {
    ar(next_step, step_times, inbox, received, applied_sequence, sent_sequence, counters.steps_processed,
       counters.rejected.by_kind, counters.peer_messages_late, rendezvous_logged, bytes_sent_to, bytes_received_from);
    cooperation.Io(ar);
    joint_tracker.Io(ar);
    filter->Io(ar);
  }

  static std::uint64_t Total(const std::map<std::string, std::uint64_t>& by_peer) {
    std::uint64_t sum = 0;
    for (const auto& [peer, bytes] : by_peer) sum += bytes;
    return sum;
  }

  // After the last step, with a folder: the raw measurements held, for a batch solve of them.
  void WriteHeldFactors(std::uint32_t k) const {
    if (options.factors_dir.empty()) return;
    std::filesystem::create_directories(options.factors_dir);
    const std::string path = cooperation::HeldFactorsPath(options.factors_dir, agent.robot_id);
    cooperation::WriteHeldFactors(path, k,
                                  {agent.robot_id, cooperation.exchange().logs(), bytes_sent_to, bytes_received_from});
    const auto& x = cooperation.exchange();
    spdlog::info("wrote the raw measurements held ({} robots) to {}; steps sent {}, taken in {}, received again {}",
                 x.logs().size(), path, x.steps_sent(), x.steps_received(), x.steps_again());
  }

  std::string SnapshotPath() const {
    return (std::filesystem::path(options.snapshot_dir) / (agent.robot_id + ".snapshot")).string();
  }

  // After step k, every snapshot_every_steps steps: the state to disk, atomically.
  void WriteSnapshot(std::uint32_t k) {
    if (options.snapshot_dir.empty() || options.snapshot_every_steps == 0 || k % options.snapshot_every_steps != 0)
      return;
    common::Archive ar = common::Archive::ForWriting();
    Io(ar);
    common::WriteSnapshot(SnapshotPath(), options.run_fingerprint, {k, ar.bytes()});
  }

  // At the start: the snapshot of this run in the folder, if there is one; the agent goes on
  // from the step after it.
  void RestoreSnapshot() {
    if (options.snapshot_dir.empty()) return;
    std::filesystem::create_directories(options.snapshot_dir);
    const auto snapshot = common::ReadSnapshot(SnapshotPath(), options.run_fingerprint);
    if (!snapshot) return;
    common::Archive ar = common::Archive::ForReading(snapshot->payload);
    try {
      Io(ar);
    } catch (const common::ArchiveError& e) {
      throw AgentError("snapshot " + SnapshotPath() + ": " + e.what());
    }
    if (!ar.AtEnd() || next_step != snapshot->step + 1) {
      throw AgentError("snapshot " + SnapshotPath() + ": does not read back as this agent's state");
    }
    restored_step = snapshot->step;
    spdlog::info("restored the snapshot of step {}: going on from step {}", restored_step, next_step);
  }

  // Why no step came within the timeout: the simulator silent, or (a restarted agent that was down
  // too long) the step it needs gone from the DDS history while later ones are there.
  std::string NoStepWhy() const {
    if (!clock.empty() && clock.begin()->first > next_step) {
      return fmt::format(
          "step {} is no longer in the DDS history (the oldest held is step {}): the agent cannot catch up "
          "(run.history_steps = {})",
          next_step, clock.begin()->first, options.history_steps);
    }
    return fmt::format("no complete step {} within {:g} s (is world_sim running on this domain?)", next_step,
                       options.timeout_s);
  }

  // Processes the next step if all of it is here. Returns true if it did.
  // Applies the peer messages of step k-1, in a fixed order (sender, then sequence); also when
  // none came, as the own detections of the last step may pair with a peer's held ones.
  void ApplyPeerMessages(std::uint32_t k) {
    cooperation::PeerInbox in;
    if (auto it = inbox.find(k - 1); it != inbox.end()) {
      in = std::move(it->second);
      inbox.erase(it);
    }
    SortBySender(&in);
    const int before = cooperation.rejected_messages();
    const int stale_before = cooperation.stale_messages();
    const std::size_t joint_before = cooperation.joint_estimates().size();
    cooperation.Receive(in, filter.get());
    const int stale = cooperation.stale_messages() - stale_before;
    if (const int bad = cooperation.rejected_messages() - before - stale; bad > 0) {
      Reject(cooperation::Rejection::kMalformed, fmt::format("{} peer message(s) of step {}", bad, k - 1),
             static_cast<std::uint32_t>(bad));
    }
    if (stale > 0) {
      Reject(cooperation::Rejection::kStale,
             fmt::format("{} peer message(s) of step {} out of order (older than one applied, or from a peer "
                         "whose frame is not known yet)",
                         stale, k - 1),
             static_cast<std::uint32_t>(stale));
    }
    for (std::size_t i = joint_before; i < cooperation.joint_estimates().size(); ++i) {
      const auto& t = cooperation.joint_estimates()[i];
      spdlog::info("joint transform from both histories at step {}: T({} <- {}) = ({:.3f}, {:.3f}, {:.4f} rad)", t.step,
                   agent.robot_id, t.peer, t.t_self_peer.x, t.t_self_peer.y, t.t_self_peer.heading);
    }
  }

  bool TryProcess(bool* last) {
    const std::uint32_t k = next_step;
    const auto& sim = simulator.simulator();
    if (!sim || !clock.count(k) || !sensors.Has(k, *sim)) return false;
    if (!PeerMessagesComplete(clock[k])) return false;
    CheckPeerCounts(clock[k]);
    const double cpu_start_s = common::ThreadCpuSeconds();
    ApplyPeerMessages(k);
    const std::uint32_t foreign_before = counters.rejected.Of(cooperation::Rejection::kForeignWriter);
    const ReceivedSensorStep taken = sensors.Take(k, *sim, &counters.rejected);
    const common::SensorStep& step = taken.step;
    if (const auto foreign = counters.rejected.Of(cooperation::Rejection::kForeignWriter) - foreign_before;
        foreign > 0) {
      spdlog::warn("rejected (foreign-writer): {} sensor step(s) of step {} not written by the simulator", foreign, k);
    }
    *last = clock[k].last_step();
    const double time_s = clock[k].stamp().time_s();
    clock.erase(k);
    filter->Process(step);
    const filters::FilterEstimate estimate = filter->Estimate();
    cooperation::PeerOutbox outbox = cooperation.AfterStep(step, estimate);
    outbox.moved = cooperation.MovedNotices(filter->TakeMovedLandmarks(), k, time_s);
    if (cooperation::JointTracker::Enabled(agent)) TrackJoint(k, estimate);
    filters::FilterEstimate published = joint_tracker.Corrected(estimate);
    cooperation.CompleteMap(&published);
    const double step_cpu_ms = 1e3 * (common::ThreadCpuSeconds() - cpu_start_s);
    PeerMessages to_peers = Prepare(std::move(outbox));
    LogRendezvous(k, *last);
    msg::Estimate m = ToMsg(published, agent.robot_id, agent.filter.type);
    for (const auto& e : cooperation.rendezvous()) m.rendezvous().push_back(ToMsg(e));
    m.frames_known(cooperation.frames_known());
    m.data_held(DataHeldMsg(cooperation.data_held()));
    m.rejected_samples(counters.rejected.Total());
    m.step_cpu_ms(step_cpu_ms);
    m.peer_bytes_sent(Total(bytes_sent_to));
    m.peer_bytes_received(Total(bytes_received_from));
    m.peer_messages_late(counters.peer_messages_late);
    m.data_hop_us(taken.hop_us);
    m.estimator_bytes(filter->EstimatorBytes() + cooperation.exchange().HeldBytes() + cooperation.streamed_bytes());
    step_times[k] = time_s;
    if (*last) m.final_trajectory_chunks(PublishFinalTrajectory(k, time_s));
    if (!estimate_writer.Write(m)) throw AgentError("DDS refused to publish the estimate of step " + std::to_string(k));
    // The peers' messages after the estimate: they do not delay it (a first message to a peer
    // has the writers toward it opened). Only lockstep waits for the acknowledgement (realtime's
    // clock waits for nobody and announces no peer message).
    const auto sent = Send(std::move(to_peers));
    if (options.lockstep) Acknowledge(k, time_s, sent);
    ++counters.steps_processed;
    ++next_step;
    if (*last) {
      WriteHeldFactors(k);
      return true;
    }
    // Between steps (the others step meanwhile): work whose result serves the next step. Not in
    // the step's CPU, which is its own processing, from its data to its estimate (the latency
    // leaves it out); in the run's CPU.
    filter->Settle();
    WriteSnapshot(k);
    return true;
  }
};

AgentNode::AgentNode(const AgentOptions& agent, const AgentNodeOptions& options,
                     std::unique_ptr<filters::SlamFilter> filter)
    : impl_(std::make_unique<Impl>(agent, options, std::move(filter))) {
  impl_->RestoreSnapshot();
}

AgentNode::~AgentNode() = default;

const AgentCounters& AgentNode::counters() const { return impl_->counters; }

bool AgentNode::Run(const std::atomic<bool>& stop) {
  Impl& a = *impl_;
  std::uint64_t seen = 0;
  const auto timeout = std::chrono::duration<double>(a.options.timeout_s);
  const auto start = Clock::now();
  while (a.estimate_writer.MatchedReaders() < a.options.estimate_readers) {
    if (stop) return false;
    if (Clock::now() - start > timeout) {
      throw AgentError("only " + std::to_string(a.estimate_writer.MatchedReaders()) + " of " +
                       std::to_string(a.options.estimate_readers) + " estimate readers matched");
    }
    a.notifier.Wait(&seen, milliseconds(5));
  }
  a.Acknowledge(0, 0.0);  // ready: every reader exists
  spdlog::info("agent {} ready ({} filter)", a.agent.robot_id, a.agent.filter.type);
  auto last_progress = Clock::now();
  while (!stop) {
    a.Drain();
    bool last = false;
    bool progressed = false;
    while (a.TryProcess(&last)) {
      progressed = true;
      if (last) {
        a.Flush();
        spdlog::info("agent {} done: {} steps, rejected: {}, peer messages applied a step late: {}", a.agent.robot_id,
                     a.counters.steps_processed, a.counters.rejected.Describe(), a.counters.peer_messages_late);
        if (a.counters.rejected.Failing() > 0 && !a.options.allow_rejected) {
          throw AgentError("agent " + a.agent.robot_id + " rejected " + a.counters.rejected.Describe() +
                           " input(s): the run's numbers cannot be trusted (--allow-rejected accepts them)");
        }
        return true;
      }
    }
    if (progressed) last_progress = Clock::now();
    if (Clock::now() - last_progress > timeout) throw AgentError(a.NoStepWhy());
    a.notifier.Wait(&seen, milliseconds(100));
  }
  return false;
}

}  // namespace mrslam::robot_agent
