#include "world_sim/node/sim_node.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <set>
#include <thread>

#include <spdlog/spdlog.h>

#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "world_sim/core/world.h"
#include "world_sim/replay/mrclam_replay.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::world_sim {

namespace {
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

using SensorWriter = dds::Writer<msg::SensorStepPubSubType>;

// The scenario's source: the simulated world, or a recorded data set when replay is set.
std::unique_ptr<StepSource> MakeSource(const common::ScenarioOptions& s) {
  auto source = MakeStepSource(s);
  const auto* replay = dynamic_cast<const MrclamReplay*>(source.get());
  if (replay == nullptr) return source;
  for (const auto& problem : replay->problems()) spdlog::warn("skipped malformed row: {}", problem);
  spdlog::info("replaying '{}' from {} s for {} steps of {} s", s.replay.dir, s.replay.start_s, s.run.steps,
               s.replay.step_s);
  return source;
}
}  // namespace

struct SimNode::Impl {
  common::ScenarioOptions scenario;
  SimNodeOptions options;
  std::unique_ptr<StepSource> source;
  StepSource& world;
  dds::Participant participant;
  std::map<std::string, std::unique_ptr<SensorWriter>> writers;
  std::unique_ptr<dds::Writer<msg::GroundTruthPubSubType>> truth;
  std::unique_ptr<dds::Writer<msg::StepClockPubSubType>> clock;
  std::map<std::string, std::unique_ptr<dds::Reader<msg::StepAckPubSubType>>> acks;

  Impl(const common::ScenarioOptions& s, const SimNodeOptions& o)
      : scenario(s),
        options(o),
        source(MakeSource(s)),
        world(*source),
        participant({o.domain, "world_sim", o.shared_memory, o.security_dir, "world_sim", s.run.history_steps}) {
    // In realtime the streams written every step are acknowledged once a second (participant.h).
    const auto ack =
        s.run.mode == common::RunMode::kRealtime ? dds::Acknowledgment::kPerSecond : dds::Acknowledgment::kPrompt;
    for (const auto& r : s.robots) {
      writers[r.id] = std::make_unique<SensorWriter>(participant, dds::SensorTopic(r.id), dds::History::kRecent, ack);
    }
    truth = std::make_unique<dds::Writer<msg::GroundTruthPubSubType>>(participant, dds::kTruthTopic,
                                                                      dds::History::kRecent, ack);
    clock = std::make_unique<dds::Writer<msg::StepClockPubSubType>>(participant, dds::kClockTopic,
                                                                    dds::History::kRecent, ack);
    for (const auto& id : o.agents) {
      acks[id] = std::make_unique<dds::Reader<msg::StepAckPubSubType>>(participant, dds::AckTopic(id));
    }
  }

  template <typename W, typename M>
  static void WriteOrThrow(W& writer, const M& message, const std::string& what) {
    if (!writer.Write(message)) throw SimError("DDS refused to publish " + what);
  }

  // Waits until every agent has acknowledged `step`; collects their peer-message counts.
  // Returns false when stopped; throws SimError naming a silent agent.
  bool WaitForAcks(std::uint32_t step, const std::atomic<bool>& stop, std::vector<msg::PeerDelivery>* deliveries) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(scenario.run.ack_timeout_s));
    for (const auto& [id, reader] : acks) {
      while (true) {
        if (stop) return false;
        msg::StepAck ack;
        if (reader->Take(&ack, milliseconds(50))) {
          if (ack.stamp().robot_id() != id) {
            spdlog::warn("ack on {}'s topic claims robot '{}': ignored", id, ack.stamp().robot_id());
            continue;
          }
          if (ack.stamp().step() < step) continue;  // an old acknowledgement (replayed history)
          if (ack.stamp().step() > step) {
            throw SimError("agent '" + id + "' acknowledged step " + std::to_string(ack.stamp().step()) +
                           " before step " + std::to_string(step) + " was published");
          }
          if (deliveries != nullptr) {
            for (const auto& pc : ack.peer_messages_sent()) {
              msg::PeerDelivery d;
              d.sender_id(id);
              d.recipient_id(pc.peer_id());
              d.count(pc.count());
              deliveries->push_back(d);
            }
          }
          break;
        }
        if (Clock::now() > deadline) {
          throw SimError("agent '" + id + "' did not acknowledge step " + std::to_string(step) + " within " +
                         fmt::format("{:g}", scenario.run.ack_timeout_s) + " s");
        }
      }
    }
    return true;
  }

  // Waits until options.truth_readers readers have matched the truth topic.
  bool WaitForTruthReaders(const std::atomic<bool>& stop) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(scenario.run.ack_timeout_s));
    while (truth->MatchedReaders() < options.truth_readers) {
      if (stop) return false;
      if (Clock::now() > deadline) {
        throw SimError("only " + std::to_string(truth->MatchedReaders()) + " of " +
                       std::to_string(options.truth_readers) + " truth readers matched within " +
                       fmt::format("{:g}", scenario.run.ack_timeout_s) + " s");
      }
      std::this_thread::sleep_for(milliseconds(5));
    }
    return true;
  }

  // Robot i's sensor step (odometry, IMU and lidar in one message).
  void PublishRobot(std::size_t i, const common::SensorStep& sample) {
    const auto& id = scenario.robots[i].id;
    WriteOrThrow(*writers.at(id), dds::ToMsg(sample), id + "'s sensor step");
  }

  // The step's truth and clock.
  void PublishStep(const std::vector<msg::PeerDelivery>& deliveries) {
    WriteOrThrow(*truth, dds::ToMsg(world.Truth()), "ground truth");
    msg::StepClock c;
    c.stamp().robot_id("world");
    c.stamp().step(world.step());
    c.stamp().time_s(world.time_s());
    c.total_steps(static_cast<std::uint32_t>(scenario.run.steps));
    c.last_step(static_cast<int>(world.step()) == scenario.run.steps);
    c.peer_deliveries(deliveries);
    WriteOrThrow(*clock, c, "step clock");
  }

  // Every robot's sensor data, then the step's truth and clock.
  void Publish(const std::vector<common::SensorStep>& samples, const std::vector<msg::PeerDelivery>& deliveries) {
    for (std::size_t i = 0; i < samples.size(); ++i) PublishRobot(i, samples[i]);
    PublishStep(deliveries);
  }

  // The step's truth and clock at `start`, then robot i's sensor data at start + i / n of the
  // period (robots whose sensors are not synchronized). False when stopped.
  bool PublishStaggered(const std::vector<common::SensorStep>& samples, Clock::time_point start, Clock::duration period,
                        const std::atomic<bool>& stop) {
    PublishStep({});
    const auto n = static_cast<Clock::rep>(samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (!SleepUntil(start + period * static_cast<Clock::rep>(i) / n, stop)) return false;
      PublishRobot(i, samples[i]);
    }
    return true;
  }

  // Sleeps until `due`, looking at `stop` every 50 ms; false when stopped.
  static bool SleepUntil(Clock::time_point due, const std::atomic<bool>& stop) {
    while (Clock::now() < due) {
      if (stop) return false;
      std::this_thread::sleep_until(std::min(due, Clock::now() + milliseconds(50)));
    }
    return !stop;
  }
};

SimNode::SimNode(const common::ScenarioOptions& scenario, const SimNodeOptions& options)
    : impl_(new Impl(scenario, options)) {}

SimNode::~SimNode() { delete impl_; }

bool SimNode::Run(const std::atomic<bool>& stop) {
  Impl& s = *impl_;
  const bool lockstep = s.scenario.run.mode == common::RunMode::kLockstep;
  const int steps = s.scenario.run.steps;
  spdlog::info("scenario '{}', seed {}, {} steps of {} s, {} mode, agents: {}", s.scenario.name, s.scenario.seed, steps,
               s.scenario.run.dt_s, lockstep ? "lockstep" : "realtime",
               s.options.agents.empty() ? std::string("none") : fmt::format("{}", fmt::join(s.options.agents, ", ")));
  // Step 0: every agent says it is ready (its readers exist).
  if (!s.WaitForAcks(0, stop, nullptr)) return false;
  spdlog::info("all agents ready");
  if (!s.WaitForTruthReaders(stop)) return false;

  // The initial truth (step 0), so that the evaluator knows where everything started.
  if (!s.truth->Write(dds::ToMsg(s.world.Truth()))) throw SimError("DDS refused to publish ground truth");

  const auto start = Clock::now();
  std::vector<msg::PeerDelivery> deliveries;
  std::vector<double> ack_latency_ms;
  int last_percent = -1;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(s.scenario.run.dt_s / s.scenario.run.realtime_factor));
  const bool staggered = !lockstep && s.scenario.run.stagger_robots;
  for (int k = 1; k <= steps; ++k) {
    if (stop) return false;
    const auto samples = s.world.Step();
    const auto published = Clock::now();
    if (staggered) {
      if (!s.PublishStaggered(samples, start + period * (k - 1), period, stop)) return false;
    } else {
      s.Publish(samples, deliveries);
    }
    deliveries.clear();
    if (lockstep) {
      if (!s.WaitForAcks(static_cast<std::uint32_t>(k), stop, &deliveries)) return false;
      ack_latency_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - published).count());
    } else if (!s.SleepUntil(start + period * k, stop)) {
      return false;
    }
    const int percent = 100 * k / steps;
    if (percent / 10 != last_percent / 10) {
      spdlog::info("step {}/{} ({}%)", k, steps, percent);
      last_percent = percent;
    }
  }
  if (const auto* replay = dynamic_cast<const MrclamReplay*>(s.source.get())) {
    spdlog::info("replay: {} measurements published; dropped {} of unknown barcodes, {} of robots not replayed",
                 replay->stats().measurements, replay->stats().unknown_barcodes, replay->stats().robots_not_replayed);
  }
  if (!ack_latency_ms.empty()) {
    std::sort(ack_latency_ms.begin(), ack_latency_ms.end());
    spdlog::info("step round trip (publish to last ack): median {:.2f} ms, max {:.2f} ms",
                 ack_latency_ms[ack_latency_ms.size() / 2], ack_latency_ms.back());
  }
  // Let every matched reader (the evaluator) receive everything before the writers go away.
  const auto drain = std::chrono::duration_cast<milliseconds>(std::chrono::duration<double>(s.options.drain_timeout_s));
  bool drained = s.truth->WaitForAcknowledgments(drain) && s.clock->WaitForAcknowledgments(drain);
  for (auto& [id, w] : s.writers) drained = w->WaitForAcknowledgments(drain) && drained;
  if (!drained) {
    spdlog::warn("some readers did not acknowledge every sample within {} s", s.options.drain_timeout_s);
  }
  spdlog::info("run complete: {} steps in {:.2f} s", steps,
               std::chrono::duration<double>(Clock::now() - start).count());
  return true;
}

}  // namespace mrslam::world_sim
