#pragma once

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <typeindex>
#include <utility>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "common/sensor_types.h"

// The only DDS plumbing of the project: one participant per process built from the XML
// profiles in config/dds_profiles.xml, and typed RAII writers and readers. Nodes use these;
// the pure cores never see them.
namespace mrslam::dds {

// Thrown when a DDS entity cannot be created (start-up only).
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The domain a process joins: the scenario's, overridden by --domain (flag >= 0), overridden
// by the environment variable MRSLAM_DOMAIN. Throws DdsError outside 0..232.
int ResolveDomain(int scenario_domain, int flag_domain);

// Path of the XML profiles: MRSLAM_DDS_PROFILES if set, else config/dds_profiles.xml of the
// source tree this binary was built from.
std::string ProfilesPath();

struct ParticipantOptions {
  int domain = 0;
  std::string name = "mrslam";
  bool shared_memory = false;  // default transports are UDPv4 only
  // DDS-Security (docs/security.md): off when empty; else the folder of the identities and the
  // process identity (world_sim, evaluator, monitor or a robot id) whose files to use.
  std::string security_dir{};
  std::string identity{};
  // The history depth of the streams it writes and reads (History::kRecent): the samples each
  // keeps for a reader that joins late (a restarted process), and so the memory of the DDS layer.
  // 0: the profiles' depth (which covers a whole run).
  int history_steps = 0;
  // HOST:PORT where this participant serves discovery to the run's others (docs/dds.md,
  // "Discovery"); empty: it discovers as MRSLAM_DISCOVERY_SERVER says (through that server when
  // set, else by announcements to every participant).
  std::string serve_discovery_at{};
};

// How much of a stream DDS keeps: the participant's history_steps, or (a stream written once at
// the end, e.g. a final trajectory in chunks) the profiles' whole-run depth.
enum class History { kRecent, kWhole };

// When a writer asks its readers to acknowledge. kPrompt: a heartbeat 20 ms after a sample not yet
// acknowledged (the profiles'), and one with every sample once the history is full. kPerSecond: one
// heartbeat a second and none with the samples, for a stream written every step of a realtime run,
// where nothing waits for an acknowledgement before the run's end: a heartbeat and an
// acknowledgement per sample would triple the datagrams (docs/dds.md). A lost sample is then sent
// again within a second.
enum class Acknowledgment { kPrompt, kPerSecond };

// Owns one DomainParticipant, its publisher, subscriber and topics; deletes everything it
// created on destruction. With a security folder, checks the identity's files first (one-line
// DdsError naming the file and the problem) and joins with DDS-Security on. Not copyable. Writers and readers it makes
// must not outlive it.
class Participant {
 public:
  explicit Participant(const ParticipantOptions& options);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  eprosima::fastdds::dds::DomainParticipant* get() { return participant_; }
  eprosima::fastdds::dds::Publisher* publisher() { return publisher_; }
  eprosima::fastdds::dds::Subscriber* subscriber() { return subscriber_; }

  // The topic `name` of type PubSubType, created once per name; the type is constructed and
  // registered once per participant: a generated type support computes its largest serialized
  // size when constructed, a loop over every bound of its nested sequences (about 10 ms for a
  // factor batch, once per peer's reader it was half of a 32-robot run's start). Threads may
  // make writers and readers at once.
  template <typename PubSubType>
  eprosima::fastdds::dds::Topic* GetTopic(const std::string& name) {
    const std::lock_guard<std::mutex> lock(topics_mutex_);
    auto type = type_names_.find(typeid(PubSubType));
    if (type == type_names_.end()) {
      type =
          type_names_.emplace(typeid(PubSubType), RegisterType(eprosima::fastdds::dds::TypeSupport(new PubSubType())))
              .first;
    }
    return GetTopic(name, type->second);
  }

  // The profiles' writer and reader QoS with the history depth `history` asks for.
  eprosima::fastdds::dds::DataWriterQos WriterQos(History history,
                                                  Acknowledgment acknowledgment = Acknowledgment::kPrompt) const;
  eprosima::fastdds::dds::DataReaderQos ReaderQos(History history) const;

 private:
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  // Registers the type with the participant unless it is already; returns its name.
  std::string RegisterType(const eprosima::fastdds::dds::TypeSupport& type);
  eprosima::fastdds::dds::Topic* GetTopic(const std::string& name, const std::string& type_name);

  std::mutex topics_mutex_;  // guards topics_ and type_names_
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
  std::map<std::type_index, std::string> type_names_;
  int history_steps_ = 0;
};

constexpr char kWriterProfile[] = "mrslam_stream_writer";
constexpr char kReaderProfile[] = "mrslam_stream_reader";

// A typed writer on one topic. Write() returns false when DDS refuses the sample.
template <typename PubSubType>
class Writer {
 public:
  using Msg = typename PubSubType::type;
  Writer(Participant& participant, const std::string& topic, History history = History::kRecent,
         Acknowledgment acknowledgment = Acknowledgment::kPrompt)
      : participant_(participant) {
    auto* t = participant.GetTopic<PubSubType>(topic);
    writer_ = participant.publisher()->create_datawriter(t, participant.WriterQos(history, acknowledgment));
    if (writer_ == nullptr) throw DdsError("cannot create a writer on topic '" + topic + "'");
  }
  // The history is emptied first: Fast DDS 2.9's writer deletion releases the samples one by one
  // while its heartbeat timer may still walk them, which was seen to spin for ever
  // (docs/faults.md, Teardown).
  ~Writer() {
    std::size_t removed = 0;
    writer_->clear_history(&removed);
    participant_.publisher()->delete_datawriter(writer_);
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  bool Write(const Msg& msg) { return writer_->write(const_cast<Msg*>(&msg)); }
  int MatchedReaders() const {
    eprosima::fastdds::dds::PublicationMatchedStatus s;
    writer_->get_publication_matched_status(s);
    return s.current_count;
  }
  // Waits until every matched reader has acknowledged every sample, or the timeout.
  bool WaitForAcknowledgments(std::chrono::milliseconds timeout) {
    const auto secs = std::chrono::duration<double>(timeout).count();
    return writer_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(secs)) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  }

 private:
  Participant& participant_;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
};

// Wakes one consumer thread when any of several readers receives data (a generation counter
// under a mutex, so no wake-up is lost between a check and a wait).
class Notifier {
 public:
  void Notify() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++generation_;
    }
    cv_.notify_all();
  }
  // Waits until the generation differs from *seen (then updates it) or the timeout.
  bool Wait(std::uint64_t* seen, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    const bool changed = cv_.wait_for(lock, timeout, [&] { return generation_ != *seen; });
    *seen = generation_;
    return changed;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::uint64_t generation_ = 0;
};

// When a sample was written (the writer's clock, DDS's source timestamp) and when this process
// received it, in nanoseconds since the Unix epoch (system clocks: comparable on one host).
struct SampleTimes {
  std::int64_t written_ns = 0;
  std::int64_t received_ns = 0;

  // The sample's DDS hop, received less written, in microseconds; 0 when either is unknown.
  double HopUs() const {
    return written_ns > 0 && received_ns > 0 ? static_cast<double>(received_ns - written_ns) * 1e-3 : 0.0;
  }
};

// A typed reader that queues every valid sample as it arrives (listener thread) for the owner
// to take (its own thread), with a timeout. Never throws out of the listener.
template <typename PubSubType>
class Reader : public eprosima::fastdds::dds::DataReaderListener {
 public:
  using Msg = typename PubSubType::type;
  Reader(Participant& participant, const std::string& topic, Notifier* notifier = nullptr,
         History history = History::kRecent)
      : participant_(participant), notifier_(notifier) {
    auto* t = participant.GetTopic<PubSubType>(topic);
    reader_ = participant.subscriber()->create_datareader(t, participant.ReaderQos(history), this,
                                                          eprosima::fastdds::dds::StatusMask::data_available());
    if (reader_ == nullptr) throw DdsError("cannot create a reader on topic '" + topic + "'");
  }
  ~Reader() override {
    reader_->set_listener(nullptr);
    participant_.subscriber()->delete_datareader(reader_);
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  // Takes the oldest queued sample (and, if asked, the participant that wrote it and when it was
  // written and received); waits up to timeout (0: does not wait, nor enter the kernel). False on
  // timeout.
  bool Take(Msg* out, std::chrono::milliseconds timeout, common::WriterId* writer = nullptr,
            SampleTimes* times = nullptr) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto ready = [this] { return !queue_.empty(); };
    if (timeout.count() == 0 ? !ready() : !cv_.wait_for(lock, timeout, ready)) return false;
    Received& front = queue_.front();
    *out = std::move(front.msg);
    if (writer != nullptr) *writer = front.writer;
    if (times != nullptr) *times = front.times;
    queue_.pop_front();
    return true;
  }
  bool TryTake(Msg* out, common::WriterId* writer = nullptr, SampleTimes* times = nullptr) {
    return Take(out, std::chrono::milliseconds(0), writer, times);
  }
  int MatchedWriters() const {
    eprosima::fastdds::dds::SubscriptionMatchedStatus s;
    reader_->get_subscription_matched_status(s);
    return s.current_count;
  }

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    Msg msg;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&msg, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      Received received{std::move(msg), {}, {info.source_timestamp.to_ns(), NowNs()}};
      const auto& prefix = info.sample_identity.writer_guid().guidPrefix.value;
      std::copy(std::begin(prefix), std::end(prefix), received.writer.begin());
      {
        std::lock_guard<std::mutex> lock(mutex_);
        queue_.push_back(std::move(received));
      }
      cv_.notify_all();
      if (notifier_ != nullptr) notifier_->Notify();
    }
  }

 private:
  struct Received {
    Msg msg;
    common::WriterId writer{};
    SampleTimes times;
  };
  static std::int64_t NowNs() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  }

  Participant& participant_;
  Notifier* notifier_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Received> queue_;
};

// Topic names (docs/dds.md).
std::string SensorTopic(const std::string& robot_id);
std::string EstimateTopic(const std::string& robot_id);
std::string FinalTrajectoryTopic(const std::string& robot_id);
std::string AckTopic(const std::string& robot_id);
// One sender's topic into one recipient for one kind of peer message:
// mrslam/peer/<recipient>/from/<sender>/<kind>. Permissions bind the sender to its identity.
std::string PeerTopic(const std::string& recipient_id, const std::string& sender_id, const std::string& kind);
constexpr char kTruthTopic[] = "mrslam/world/truth";
constexpr char kClockTopic[] = "mrslam/world/clock";

}  // namespace mrslam::dds
