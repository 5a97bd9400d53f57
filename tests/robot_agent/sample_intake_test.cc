#include "robot_agent/cooperation/sample_intake.h"

#include <gtest/gtest.h>

namespace mrslam::robot_agent::cooperation {
namespace {

const WriterId kSimulator{1, 2, 3};
const WriterId kOutsider{9, 9, 9};

TEST(StepSlotsTest, TakesTheSimulatorsSampleAndCountsTheOthersAsForeign) {
  StepSlots<int> slots(10);
  EXPECT_EQ(slots.Offer(3, 1, kOutsider, 66), std::nullopt);  // who is who is known only later
  EXPECT_EQ(slots.Offer(3, 1, kSimulator, 7), std::nullopt);
  EXPECT_FALSE(slots.Has(2, kSimulator));
  EXPECT_FALSE(slots.Has(3, WriterId{5}));
  ASSERT_TRUE(slots.Has(3, kSimulator));
  RejectionCounts counts;
  EXPECT_EQ(slots.Take(3, kSimulator, &counts), 7);
  EXPECT_EQ(counts.Of(Rejection::kForeignWriter), 1U);
  EXPECT_FALSE(slots.Has(3, kSimulator));
}

TEST(StepSlotsTest, RejectsStaleDuplicateBeyondTheHorizonAndTooManyWriters) {
  StepSlots<int> slots(10);
  EXPECT_EQ(slots.Offer(4, 5, kSimulator, 1), Rejection::kStale);
  EXPECT_EQ(slots.Offer(15, 5, kSimulator, 1), std::nullopt);  // exactly at the horizon
  EXPECT_EQ(slots.Offer(16, 5, kSimulator, 1), Rejection::kBeyondHorizon);
  EXPECT_EQ(slots.Offer(4000000000U, 5, kSimulator, 1), Rejection::kBeyondHorizon);
  EXPECT_EQ(slots.Offer(15, 5, kSimulator, 2), Rejection::kDuplicate);
  for (std::uint8_t w = 10; w < 13; ++w) EXPECT_EQ(slots.Offer(15, 5, WriterId{w}, 3), std::nullopt);
  EXPECT_EQ(slots.Offer(15, 5, WriterId{20}, 3), Rejection::kForeignWriter);
}

TEST(SimulatorBindingTest, TheFirstClockWriterIsTheSimulatorAndASecondIsContested) {
  SimulatorBinding binding;
  EXPECT_FALSE(binding.simulator().has_value());
  EXPECT_EQ(binding.OfferClock(kSimulator), std::nullopt);
  EXPECT_EQ(binding.OfferClock(kSimulator), std::nullopt);
  EXPECT_EQ(binding.OfferClock(kOutsider), Rejection::kContested);
  EXPECT_EQ(binding.simulator(), kSimulator);
}

TEST(RejectionCountsTest, OnlyStaleAndDuplicateDoNotFailARun) {
  RejectionCounts counts;
  EXPECT_EQ(counts.Describe(), "none");
  counts.Add(Rejection::kStale, 4);
  counts.Add(Rejection::kDuplicate);
  EXPECT_EQ(counts.Failing(), 0U);
  counts.Add(Rejection::kContested, 2);
  counts.Add(Rejection::kMalformed);
  EXPECT_EQ(counts.Total(), 8U);
  EXPECT_EQ(counts.Failing(), 3U);
  EXPECT_EQ(counts.Describe(), "1 malformed, 2 contested, 4 stale, 1 duplicate");
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
