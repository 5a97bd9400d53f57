#include "world_sim/evaluator/delivery_timing.h"

#include <limits>

#include <gtest/gtest.h>

namespace mrslam::evaluator {
namespace {

constexpr std::int64_t kStart = 1'700'000'000'000'000'000;  // a plausible epoch time, ns
constexpr std::int64_t kStepNs = 100'000'000;               // 10 Hz

// Steps 1..n written every 100 ms, each robot's odometry 50 us before the step's truth.
DeliveryTiming Steps(int n) {
  DeliveryTiming timing({"r1"});
  for (int k = 1; k <= n; ++k) {
    const std::int64_t t = kStart + k * kStepNs;
    timing.SensorWritten("r1", k, t - 50'000);
    timing.StepWritten(k, t);
  }
  return timing;
}

TEST(DeliveryTimingTest, LatencyIsReceptionAfterTheStepMinusProcessing) {
  DeliveryTiming timing = Steps(100);
  // Step k's estimate: 2 ms of processing, received 2.3 ms + k us after the step was written.
  for (int k = 1; k <= 100; ++k) {
    const std::int64_t step_ns = kStart + k * kStepNs;
    const std::int64_t received = step_ns + 2'300'000 + std::int64_t{k} * 1000;
    // Written 10 us before its reception, every fourth 100 us before (median 10 us, mean 32.5 us).
    timing.EstimateDelivered("r1", k, {received - (k % 4 == 0 ? 100'000 : 10'000), received, 2.0});
  }
  const DeliverySummary s = timing.Summary("r1");
  EXPECT_EQ(s.timed_steps, 100U);
  EXPECT_LE(timing.Held(), 2U);  // the last step's times: nothing is kept once it has been used
  // Latencies 300 + k us, k = 1..100: median 350.5, 99th percentile 300 + 1 + 0.99 * 99.
  EXPECT_NEAR(s.latency_us_median, 350.5, 1e-6);
  EXPECT_NEAR(s.latency_us_p99, 301.0 + 0.99 * 99.0, 1e-6);
  EXPECT_EQ(s.late_estimates, 0);
  EXPECT_NEAR(s.estimate_hop_us_median, 10.0, 1e-6);
}

TEST(DeliveryTimingTest, AnEstimateWrittenAfterTheNextStepsSensorDataIsLate) {
  DeliveryTiming timing = Steps(10);
  for (int k = 1; k <= 10; ++k) {
    const std::int64_t next_sensor = kStart + (k + 1) * kStepNs - 50'000;
    // Steps 3 and 7 are written 1 us after the next step's odometry; the others 1 us before.
    const std::int64_t written = (k == 3 || k == 7) ? next_sensor + 1000 : next_sensor - 1000;
    timing.EstimateDelivered("r1", k, {written, written + 100'000, 1.0});
  }
  EXPECT_EQ(timing.Summary("r1").late_estimates, 2);
  EXPECT_EQ(timing.Summary("r1").late_steps, (std::vector<std::uint32_t>{3, 7}));
}

TEST(DeliveryTimingTest, NamesTheStepsOfTheFirstLateEstimatesOnly) {
  const int n = static_cast<int>(kMaxLateSteps) + 10;
  DeliveryTiming timing = Steps(n + 1);
  for (int k = 1; k <= n; ++k) {  // every one written after the next step's odometry
    const std::int64_t written = kStart + (k + 1) * kStepNs;
    timing.EstimateDelivered("r1", k, {written, written + 100'000, 1.0});
  }
  const DeliverySummary s = timing.Summary("r1");
  EXPECT_EQ(s.late_estimates, n);
  ASSERT_EQ(s.late_steps.size(), kMaxLateSteps);
  EXPECT_EQ(s.late_steps.front(), 1U);
  EXPECT_EQ(s.late_steps.back(), kMaxLateSteps);
}

TEST(DeliveryTimingTest, SensorDataTakenAfterItsOwnStepsEstimateStillJudgesTheOneBefore) {
  DeliveryTiming timing({"r1"});
  // Taken in batches, each step's estimate before the same step's odometry. Step 4's estimate
  // is written after step 5's odometry (late); the others 1 ms after their own step's.
  for (int k = 1; k <= 10; ++k) {
    const std::int64_t sensor = kStart + k * kStepNs - 50'000;
    timing.StepWritten(k, kStart + k * kStepNs);
    const std::int64_t written = k == 4 ? kStart + 5 * kStepNs : sensor + 1'000'000;
    timing.EstimateDelivered("r1", k, {written, written + 100'000, 1.0});
    timing.SensorWritten("r1", k, sensor);
  }
  EXPECT_EQ(timing.Summary("r1").late_estimates, 1);
  EXPECT_EQ(timing.Summary("r1").late_steps, std::vector<std::uint32_t>{4});
  EXPECT_LE(timing.Held(), 1U);  // only step 10's estimate, awaiting step 11's odometry
}

TEST(DeliveryTimingTest, AnEstimateBeforeItsStepsTruthIsTimedWhenTheTruthComes) {
  DeliveryTiming timing({"r1", "r2"});
  timing.SensorWritten("r1", 1, kStart - 50'000);
  timing.SensorWritten("r2", 1, kStart - 40'000);
  timing.EstimateDelivered("r1", 1, {kStart + 900'000, kStart + 1'000'000, 0.5});
  EXPECT_EQ(timing.Summary("r1").timed_steps, 0U);
  timing.StepWritten(1, kStart);
  EXPECT_EQ(timing.Summary("r1").timed_steps, 1U);
  EXPECT_NEAR(timing.Summary("r1").latency_us_median, 500.0, 1e-6);  // 1000 us less 0.5 ms
  // r2 has not reported step 1 yet: its time is still held for r2.
  timing.EstimateDelivered("r2", 1, {kStart + 1'900'000, kStart + 2'000'000, 0.25});
  EXPECT_NEAR(timing.Summary("r2").latency_us_median, 1750.0, 1e-6);
}

TEST(DeliveryTimingTest, ARobotWhoseDataComeLaterInTheStepIsTimedFromItsData) {
  // Staggered: the step's truth and clock at kStart, r1's data then, r2's 50 ms later.
  DeliveryTiming timing({"r1", "r2"});
  timing.StepWritten(1, kStart);
  timing.SensorWritten("r1", 1, kStart + 20'000);
  timing.SensorWritten("r2", 1, kStart + 50'000'000);
  timing.EstimateDelivered("r1", 1, {kStart + 1'900'000, kStart + 2'000'000, 1.5});
  timing.EstimateDelivered("r2", 1, {kStart + 51'900'000, kStart + 52'000'000, 1.5});
  EXPECT_NEAR(timing.Summary("r1").latency_us_median, 480.0, 1e-6);  // 2000 - 20 - 1500 us
  EXPECT_NEAR(timing.Summary("r2").latency_us_median, 500.0, 1e-6);  // 52000 - 50000 - 1500 us
}

TEST(DeliveryTimingTest, AnEstimateTakenBeforeItsOwnDataIsTimedWhenTheDataCome) {
  // Taken in batches: each robot's estimate of step k before its odometry of step k; every
  // robot is past step k (so the step's truth must still be held for the latency).
  DeliveryTiming timing({"r1", "r2"});
  for (int k = 1; k <= 5; ++k) {
    const std::int64_t step_ns = kStart + k * kStepNs;
    timing.StepWritten(k, step_ns);
    for (const char* id : {"r1", "r2"}) timing.EstimateDelivered(id, k, {step_ns + 900'000, step_ns + 1'000'000, 0.6});
    timing.SensorWritten("r1", k, step_ns - 30'000);
    timing.SensorWritten("r2", k, step_ns + 100'000);
  }
  EXPECT_EQ(timing.Summary("r1").timed_steps, 5U);
  EXPECT_NEAR(timing.Summary("r1").latency_us_median, 400.0, 1e-6);  // from the truth, written later
  EXPECT_NEAR(timing.Summary("r2").latency_us_median, 300.0, 1e-6);  // from its data
  EXPECT_LE(timing.Held(), 3U);  // step 5's truth and the estimates awaiting step 6's odometry
}

TEST(DeliveryTimingTest, TheLatencySplitsIntoBothHopsAndTheAgentsOverhead) {
  DeliveryTiming timing = Steps(9);
  // Step k: the data's hop 100 + 10 k us, the estimate's 50 us, latency 400 + 20 k us (its data
  // written 50 us before the step's truth: timed from the truth), so the agent's overhead is
  // 250 + 10 k us. Step 9 reports no data hop (an older agent): timed, but not split.
  for (int k = 1; k <= 9; ++k) {
    const std::int64_t received = kStart + k * kStepNs + 1'400'000 + std::int64_t{k} * 20'000;
    const double data_hop_us = k == 9 ? 0.0 : 100.0 + 10.0 * k;
    timing.EstimateDelivered("r1", k, {received - 50'000, received, 1.0, data_hop_us});
  }
  const DeliverySummary s = timing.Summary("r1");
  EXPECT_EQ(s.timed_steps, 9U);
  EXPECT_NEAR(s.latency_us_median, 500.0, 1e-6);   // k = 5 of 1..9
  EXPECT_NEAR(s.data_hop_us_median, 145.0, 1e-6);  // k = 1..8: 110..180
  EXPECT_NEAR(s.estimate_hop_us_median, 50.0, 1e-6);
  EXPECT_NEAR(s.agent_overhead_us_median, 295.0, 1e-6);  // k = 1..8: 260..330
}

TEST(DeliveryTimingTest, ANonFiniteProcessingTimeOrDataHopIsLeftOut) {
  DeliveryTiming timing = Steps(2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  timing.EstimateDelivered("r1", 1, {kStart + kStepNs, kStart + kStepNs + 500'000, nan, 100.0});
  timing.EstimateDelivered("r1", 2, {kStart + 2 * kStepNs, kStart + 2 * kStepNs + 500'000, 0.1, nan});
  const DeliverySummary s = timing.Summary("r1");
  EXPECT_EQ(s.timed_steps, 1U);  // step 2 only
  EXPECT_NEAR(s.latency_us_median, 400.0, 1e-6);
  EXPECT_NEAR(s.data_hop_us_median, 100.0, 1e-6);  // step 1's: its hop is known
  EXPECT_EQ(s.agent_overhead_us_median, 0.0);      // neither step has every part
}

TEST(DeliveryTimingTest, UnknownTimesLeaveTheStepOut) {
  DeliveryTiming timing = Steps(3);
  timing.StepWritten(4, 0);  // unknown: not recorded
  timing.EstimateDelivered("r1", 1, {0, kStart + kStepNs + 500'000, 0.2});
  timing.EstimateDelivered("r1", 2, {0, 0, 0.2});
  timing.EstimateDelivered("r1", 4, {kStart, kStart + 5 * kStepNs, 0.2});
  const DeliverySummary s = timing.Summary("r1");
  EXPECT_EQ(s.timed_steps, 1U);  // only step 1 has both a step time and a reception
  EXPECT_NEAR(s.latency_us_median, 300.0, 1e-6);
  EXPECT_EQ(s.late_estimates, 0);  // no write time known where the next step's is
  EXPECT_EQ(timing.Summary("r2").timed_steps, 0U);
}

}  // namespace
}  // namespace mrslam::evaluator
