#include "scripts/view/frame_hub.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>

namespace mrslam::view {
namespace {

using std::chrono::milliseconds;

TEST(FrameHubTest, NothingBeforeTheFirstFrame) {
  FrameHub hub;
  std::uint64_t version = 0;
  std::string frame;
  EXPECT_FALSE(hub.WaitNewer(&version, &frame, milliseconds(0)));
}

TEST(FrameHubTest, AClientGetsOnlyTheLatestFrameAndEachFrameOnce) {
  FrameHub hub;
  std::uint64_t version = 0;
  std::string frame;
  hub.Publish("step 1");
  hub.Publish("step 2");
  hub.Publish("step 3");  // a slow client skips steps 1 and 2
  ASSERT_TRUE(hub.WaitNewer(&version, &frame, milliseconds(0)));
  EXPECT_EQ(frame, "step 3");
  EXPECT_FALSE(hub.WaitNewer(&version, &frame, milliseconds(0)));
  hub.Publish("step 4");
  ASSERT_TRUE(hub.WaitNewer(&version, &frame, milliseconds(0)));
  EXPECT_EQ(frame, "step 4");
}

TEST(FrameHubTest, ClientsAreIndependent) {
  FrameHub hub;
  std::uint64_t fast = 0, slow = 0;
  std::string frame;
  hub.Publish("a");
  ASSERT_TRUE(hub.WaitNewer(&fast, &frame, milliseconds(0)));
  hub.Publish("b");
  ASSERT_TRUE(hub.WaitNewer(&slow, &frame, milliseconds(0)));
  EXPECT_EQ(frame, "b");
  ASSERT_TRUE(hub.WaitNewer(&fast, &frame, milliseconds(0)));
  EXPECT_EQ(frame, "b");
}

TEST(FrameHubTest, OnceClosedTheLastFrameIsStillHandedOutThenNothing) {
  FrameHub hub;
  std::uint64_t version = 0;
  std::string frame;
  hub.Publish("last");
  hub.Close();
  EXPECT_TRUE(hub.closed());
  ASSERT_TRUE(hub.WaitNewer(&version, &frame, milliseconds(0)));
  EXPECT_EQ(frame, "last");
  // Closed: neither waits (a long timeout would hang the test).
  EXPECT_FALSE(hub.WaitNewer(&version, &frame, std::chrono::hours(1)));
  hub.Pause(std::chrono::hours(1));
}

}  // namespace
}  // namespace mrslam::view
