// The agent's writers toward its peers: opened at once where the run waits for every agent
// (lockstep), on the pool's own thread otherwise, and usable once open.
#include "robot_agent/node/peer_writer_pool.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"

namespace mrslam::robot_agent {
namespace {

using std::chrono::seconds;
using Clock = std::chrono::steady_clock;

constexpr int kDomain = 149;  // this test's own DDS domain

dds::ParticipantOptions Options(const std::string& name) {
  dds::ParticipantOptions options;
  options.domain = kDomain;
  options.name = name;
  return options;
}

// A relative measurement from r1 to r2 at step 7 (what the reader checks).
msg::RelativeMeasurement FromR1ToR2() {
  msg::RelativeMeasurement m;
  m.stamp().robot_id("r1");
  m.stamp().step(7);
  m.recipient_id("r2");
  return m;
}

TEST(PeerWriterPoolTest, WithoutItsThreadTheWritersOpenWhenAskedFor) {
  dds::Participant participant(Options("r1"));
  PeerWriterPool pool(participant, "r1", false, false);
  PeerWriters* writers = pool.Get("r2");
  ASSERT_NE(writers, nullptr);
  EXPECT_EQ(pool.Get("r2"), writers);
  EXPECT_FALSE(writers->factors.has_value());
  EXPECT_EQ(pool.Open().size(), 1u);
}

TEST(PeerWriterPoolTest, ItsThreadOpensTheWritersAndTheyReachThePeer) {
  dds::Participant sender(Options("r1"));
  dds::Participant receiver(Options("r2"));
  dds::Notifier notifier;
  PeerReaders readers(receiver, "r2", "r1", &notifier, true);
  PeerWriterPool pool(sender, "r1", true, true);
  EXPECT_EQ(pool.Get("r2"), nullptr);  // asked for; opened in the background
  ASSERT_TRUE(pool.WaitAllOpen(Clock::now() + seconds(10)));
  PeerWriters* writers = pool.Get("r2");
  ASSERT_NE(writers, nullptr);
  ASSERT_TRUE(writers->factors.has_value());
  const auto deadline = Clock::now() + seconds(10);
  while (writers->relative.MatchedReaders() == 0 && Clock::now() < deadline) {
    std::uint64_t seen = 0;
    notifier.Wait(&seen, std::chrono::milliseconds(10));
  }
  ASSERT_EQ(writers->relative.MatchedReaders(), 1);
  ASSERT_TRUE(writers->relative.Write(FromR1ToR2()));
  msg::RelativeMeasurement got;
  ASSERT_TRUE(readers.relative.Take(&got, std::chrono::milliseconds(5000)));
  EXPECT_EQ(got.stamp().robot_id(), "r1");
  EXPECT_EQ(got.stamp().step(), 7u);
  EXPECT_EQ(got.recipient_id(), "r2");
}

TEST(PeerWriterPoolTest, WaitingForWritersNeverAskedForEndsAtOnce) {
  dds::Participant participant(Options("r1"));
  PeerWriterPool pool(participant, "r1", false, true);
  EXPECT_TRUE(pool.WaitAllOpen(Clock::now()));
  EXPECT_TRUE(pool.Open().empty());
}

}  // namespace
}  // namespace mrslam::robot_agent
