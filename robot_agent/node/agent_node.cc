#include "robot_agent/node/agent_node.h"

#include <chrono>
#include <map>

#include <spdlog/spdlog.h>

#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "robot_agent/core/sample_validation.h"
#include "robot_agent/node/msg_conversion.h"

namespace mrslam::robot_agent {

namespace {
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;
}  // namespace

struct AgentNode::Impl {
  common::ScenarioOptions scenario;
  AgentNodeOptions options;
  std::unique_ptr<SlamFilter> filter;
  dds::Participant participant;
  dds::Notifier notifier;
  dds::Reader<msg::LidarScanPubSubType> lidar_reader;
  dds::Reader<msg::ImuPubSubType> imu_reader;
  dds::Reader<msg::OdometryPubSubType> odometry_reader;
  dds::Reader<msg::StepClockPubSubType> clock_reader;
  dds::Writer<msg::EstimatePubSubType> estimate_writer;
  dds::Writer<msg::StepAckPubSubType> ack_writer;
  AgentCounters counters;
  std::uint32_t next_step = 1;
  // Samples buffered by step until the step is complete.
  std::map<std::uint32_t, common::LidarScan> lidar;
  std::map<std::uint32_t, common::ImuSamples> imu;
  std::map<std::uint32_t, common::Odometry> odometry;
  std::map<std::uint32_t, msg::StepClock> clock;

  Impl(const common::ScenarioOptions& s, const AgentNodeOptions& o, std::unique_ptr<SlamFilter> f)
      : scenario(s),
        options(o),
        filter(std::move(f)),
        participant({o.domain, "robot_agent/" + o.robot_id, o.shared_memory}),
        lidar_reader(participant, dds::LidarTopic(o.robot_id), &notifier),
        imu_reader(participant, dds::ImuTopic(o.robot_id), &notifier),
        odometry_reader(participant, dds::OdometryTopic(o.robot_id), &notifier),
        clock_reader(participant, dds::kClockTopic, &notifier),
        estimate_writer(participant, dds::EstimateTopic(o.robot_id)),
        ack_writer(participant, dds::AckTopic(o.robot_id)) {}

  void Reject(const std::string& why) {
    ++counters.rejected_samples;
    spdlog::warn("rejected: {} (rejected so far: {})", why, counters.rejected_samples);
  }

  // Buffers a sample of a future or current step, or rejects it.
  template <typename T>
  void Buffer(T sample, std::map<std::uint32_t, T>* buffer, int (*sanitize)(T*), const char* what) {
    if (const auto problem = StampProblem(sample.stamp, options.robot_id, next_step); !problem.empty()) {
      Reject(std::string(what) + ": " + problem);
      return;
    }
    if (buffer->count(sample.stamp.step) != 0) {
      Reject(std::string(what) + ": a second sample of step " + std::to_string(sample.stamp.step));
      return;
    }
    if (const int bad = sanitize(&sample); bad > 0) {
      counters.rejected_samples += bad;
      spdlog::warn("rejected {} malformed {} item(s) of step {}", bad, what, sample.stamp.step);
    }
    const auto step = sample.stamp.step;
    buffer->emplace(step, std::move(sample));
  }

  void Drain() {
    msg::LidarScan l;
    while (lidar_reader.TryTake(&l)) Buffer(dds::FromMsg(l), &lidar, &SanitizeLidar, "lidar");
    msg::Imu m;
    while (imu_reader.TryTake(&m)) Buffer(dds::FromMsg(m), &imu, &SanitizeImu, "imu");
    msg::Odometry od;
    while (odometry_reader.TryTake(&od)) Buffer(dds::FromMsg(od), &odometry, &SanitizeOdometry, "odometry");
    msg::StepClock c;
    while (clock_reader.TryTake(&c)) {
      if (c.stamp().step() >= next_step) clock[c.stamp().step()] = c;
    }
  }

  void Acknowledge(std::uint32_t step, double time_s) {
    msg::StepAck ack;
    ack.stamp(dds::ToMsg(common::Stamp{options.robot_id, step, time_s}));
    ack.rejected_samples(static_cast<std::uint32_t>(counters.rejected_samples));
    if (!ack_writer.Write(ack)) throw AgentError("DDS refused to publish the acknowledgement of step " + std::to_string(step));
  }

  // Processes the next step if all of it is here. Returns true if it did.
  bool TryProcess(bool* last) {
    const std::uint32_t k = next_step;
    if (!clock.count(k) || !lidar.count(k) || !imu.count(k) || !odometry.count(k)) return false;
    common::SensorStep step{std::move(lidar[k]), std::move(imu[k]), std::move(odometry[k])};
    *last = clock[k].last_step();
    const double time_s = clock[k].stamp().time_s();
    lidar.erase(k);
    imu.erase(k);
    odometry.erase(k);
    clock.erase(k);
    filter->Process(step);
    const FilterEstimate estimate = filter->Estimate();
    msg::Estimate m = ToMsg(estimate, options.robot_id, scenario.filter.type);
    m.rejected_samples(static_cast<std::uint32_t>(counters.rejected_samples));
    if (!estimate_writer.Write(m)) throw AgentError("DDS refused to publish the estimate of step " + std::to_string(k));
    Acknowledge(k, time_s);
    ++counters.steps_processed;
    ++next_step;
    return true;
  }
};

AgentNode::AgentNode(const common::ScenarioOptions& scenario, const AgentNodeOptions& options,
                     std::unique_ptr<SlamFilter> filter)
    : impl_(std::make_unique<Impl>(scenario, options, std::move(filter))) {}

AgentNode::~AgentNode() = default;

const AgentCounters& AgentNode::counters() const { return impl_->counters; }

bool AgentNode::Run(const std::atomic<bool>& stop) {
  Impl& a = *impl_;
  a.Acknowledge(0, 0.0);  // ready: every reader exists
  spdlog::info("agent {} ready ({} filter)", a.options.robot_id, a.scenario.filter.type);
  std::uint64_t seen = 0;
  auto last_progress = Clock::now();
  const auto timeout = std::chrono::duration<double>(a.options.timeout_s);
  while (!stop) {
    a.Drain();
    bool last = false;
    bool progressed = false;
    while (a.TryProcess(&last)) {
      progressed = true;
      if (last) {
        // Let the evaluator and the simulator receive the final estimate and ack.
        a.estimate_writer.WaitForAcknowledgments(milliseconds(5000));
        a.ack_writer.WaitForAcknowledgments(milliseconds(5000));
        spdlog::info("agent {} done: {} steps, {} rejected samples", a.options.robot_id,
                     a.counters.steps_processed, a.counters.rejected_samples);
        return true;
      }
    }
    if (progressed) last_progress = Clock::now();
    if (Clock::now() - last_progress > timeout) {
      throw AgentError("no complete step " + std::to_string(a.next_step) + " within " +
                       std::to_string(a.options.timeout_s) + " s (is world_sim running on this domain?)");
    }
    a.notifier.Wait(&seen, milliseconds(100));
  }
  return false;
}

}  // namespace mrslam::robot_agent
