// Raw measurements shared peer to peer (FactorExchange), in process: what is sent within the
// window after a detection, relaying to a robot that never met the origin, a lost batch made
// good, a step reaching an agent twice entering once, and forged or malformed batches rejected
// whole.
#include "robot_agent/cooperation/factor_exchange.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace mrslam::robot_agent::cooperation {
namespace {

constexpr int kWindow = 5;

AgentOptions Options(const std::string& self, bool relay = true) {
  AgentOptions o;
  o.robot_id = self;
  o.team = {"a", "b", "c"};
  o.cooperation.share_factors = true;
  o.cooperation.exchange_window_steps = kWindow;
  o.cooperation.max_batch_steps = 50;
  o.cooperation.relay_factors = relay;
  return o;
}

// Robot `self`'s step k: one odometry segment, one labelled landmark reading and a detection of
// every robot in `sees`.
common::SensorStep Step(const std::string& self, std::uint32_t k, const std::vector<std::string>& sees = {}) {
  common::SensorStep s;
  const double t = 0.1 * k;
  s.lidar.stamp = {self, k, t};
  s.odometry.stamp = {self, k, t};
  s.odometry.segments = {{t - 0.1, 0.1, 0.5, 0.01 * k}};
  s.lidar.landmarks = {{t, 2.0 + 0.01 * k, 0.3, 7}};
  for (const auto& id : sees) s.lidar.robots.push_back({t, 1.5, -0.2, id});
  return s;
}

// Robot `self`'s estimate at step k of the landmark it labels 7 (its position drifting with k so
// that each step's estimate differs).
TrackEstimate Track(std::uint32_t k, bool moving = false) {
  TrackEstimate t;
  t.label = 7;
  t.step = k;
  t.mean = {2.0 + 0.01 * k, 0.3, 0.1};
  t.position_covariance = 0.01 * Eigen::Matrix2d::Identity();
  t.heading_var = 0.2;
  t.v_mps = moving ? 0.4 : 0.0;
  t.moving = moving;
  return t;
}

// Three agents stepping together; deliver() hands each batch of a step to its recipient unless
// the filter drops it.
class ThreeAgents {
 public:
  explicit ThreeAgents(bool relay = true) {
    for (const std::string id : {"a", "b", "c"}) agents_.emplace(id, FactorExchange(Options(id, relay)));
  }
  FactorExchange& operator[](const std::string& id) { return agents_.at(id); }

  // Step k: every agent records its step (seeing those in sees[id]) and sends; the batches reach
  // their recipients unless drop says otherwise. Returns the batches sent.
  std::vector<FactorBatch> Run(std::uint32_t k, std::map<std::string, std::vector<std::string>> sees,
                               bool (*drop)(const FactorBatch&) = nullptr) {
    std::vector<FactorBatch> sent;
    for (auto& [id, agent] : agents_) {
      agent.RecordOwn(Step(id, k, sees[id]), {Track(k)});
      for (auto& b : agent.Outgoing(k, 0.1 * k)) sent.push_back(std::move(b));
    }
    for (const auto& b : sent) {
      if (drop != nullptr && drop(b)) continue;
      EXPECT_TRUE(agents_.at(b.header.recipient).Receive(b)) << b.header.sender << " -> " << b.header.recipient;
    }
    return sent;
  }

 private:
  std::map<std::string, FactorExchange> agents_;
};

std::map<std::string, std::vector<std::string>> Mutual(const std::string& x, const std::string& y) {
  return {{x, {y}}, {y, {x}}};
}

TEST(FactorExchange, SendsWhatThePeerLacksOnlyWithinTheWindowOfADetection) {
  ThreeAgents t;
  for (std::uint32_t k = 1; k <= 4; ++k) EXPECT_TRUE(t.Run(k, {}).empty()) << "nobody has met at step " << k;
  // A greeting first: what each holds, no steps (the other may have had them from others).
  const auto first = t.Run(5, Mutual("a", "b"));
  ASSERT_EQ(first.size(), 2U);
  EXPECT_TRUE(first[0].runs.empty() && first[1].runs.empty());
  EXPECT_EQ(t["b"].Held("a"), 0U);
  // Told, each sends what the other lacks,
  t.Run(6, {});
  EXPECT_EQ(t["b"].Held("a"), 6U);
  EXPECT_EQ(t["a"].Held("b"), 6U);
  // then, at each next step of the window, only the new step.
  for (std::uint32_t k = 7; k <= 5 + kWindow; ++k) {
    for (const auto& b : t.Run(k, {})) {
      ASSERT_EQ(b.runs.size(), 1U);
      EXPECT_EQ(b.runs[0].first_step, k);
      EXPECT_EQ(b.runs[0].steps.size(), 1U);
    }
  }
  EXPECT_EQ(t["b"].Held("a"), 5U + kWindow);
  EXPECT_TRUE(t.Run(6 + kWindow, {}).empty()) << "the window has closed";
  EXPECT_EQ(t["c"].Held("a"), 0U);
  EXPECT_EQ(t["a"].steps_received(), 5U + kWindow);
  // What b holds of a is a's own log, step for step.
  const auto& mine = t["a"].logs().at("a").steps;
  const auto& theirs = t["b"].logs().at("a").steps;
  ASSERT_EQ(theirs.size(), 5U + kWindow);
  for (std::size_t i = 0; i < theirs.size(); ++i) {
    EXPECT_EQ(theirs[i].lidar.stamp.step, mine[i].lidar.stamp.step);
    EXPECT_EQ(theirs[i].odometry.segments[0].w_radps, mine[i].odometry.segments[0].w_radps);
  }
}

// a and b together for steps 1..kMet, b and c from step 30 on: b holds a's steps up to the end
// of their window.
constexpr std::uint32_t kMet = 10;
static_assert(kMet + kWindow > FactorExchange::kRelayLagSteps, "what b holds of a must be worth relaying");

TEST(FactorExchange, RelaysToARobotThatNeverMetTheOrigin) {
  ThreeAgents t;
  for (std::uint32_t k = 1; k <= kMet; ++k) t.Run(k, Mutual("a", "b"));
  for (std::uint32_t k = kMet + 1; k <= 35; ++k) {
    for (const auto& b : t.Run(k, k >= 30 ? Mutual("b", "c") : std::map<std::string, std::vector<std::string>>{})) {
      EXPECT_FALSE((b.header.sender == "a" && b.header.recipient == "c") ||
                   (b.header.sender == "c" && b.header.recipient == "a"));
    }
  }
  EXPECT_EQ(t["b"].Held("a"), kMet + kWindow);
  EXPECT_EQ(t["c"].Held("a"), kMet + kWindow);  // all of it, through b
  EXPECT_EQ(t["a"].Held("c"), 0U);
}

TEST(FactorExchange, TrackEstimatesTravelWithTheirStepsAndAreRelayed) {
  ThreeAgents t;
  for (std::uint32_t k = 1; k <= kMet; ++k) t.Run(k, Mutual("a", "b"));
  for (std::uint32_t k = kMet + 1; k <= 35; ++k) {
    t.Run(k, k >= 30 ? Mutual("b", "c") : std::map<std::string, std::vector<std::string>>{});
  }
  // A static landmark's estimate is renewed every kTrackRefreshSteps steps: a holds its newest
  // (of step 31); b and c the newest of a step they hold (a's steps 1..15: that of step 11).
  EXPECT_EQ(t["a"].logs().at("a").tracks.at(7).step, 31U);
  for (const std::string id : {"b", "c"}) {
    const auto& tracks = t[id].logs().at("a").tracks;
    ASSERT_EQ(tracks.size(), 1U) << id;
    EXPECT_EQ(tracks.at(7).step, 11U) << id;
    EXPECT_EQ(tracks.at(7).mean, SharedPrecision(Track(11)).mean) << id;
  }
}

TEST(FactorExchange, AMoversEstimateIsRenewedAtEveryStepThatReadsIt) {
  FactorExchange a(Options("a"));
  for (std::uint32_t k = 1; k <= 5; ++k) a.RecordOwn(Step("a", k), {Track(k, true)});
  EXPECT_EQ(a.logs().at("a").tracks.at(7).step, 5U);
  a.RecordOwn(Step("a", 6), {Track(5, true)});  // not of this step: not taken
  EXPECT_EQ(a.logs().at("a").tracks.at(7).step, 5U);
}

TEST(FactorExchange, AtAFirstContactOnlyWhatThePeerLacksTravels) {
  ThreeAgents t;
  for (std::uint32_t k = 1; k <= kMet; ++k) t.Run(k, Mutual("a", "b"));
  for (std::uint32_t k = kMet + 1; k <= 49; ++k)
    t.Run(k, k >= 30 && k < 36 ? Mutual("b", "c") : decltype(Mutual("b", "c")){});
  ASSERT_EQ(t["c"].Held("a"), kMet + kWindow);
  // a and c meet: after the greetings a sends c its steps from kMet + kWindow + 1 on, none twice.
  for (std::uint32_t k = 50; k <= 55; ++k) t.Run(k, Mutual("a", "c"));
  EXPECT_EQ(t["c"].Held("a"), 55U);
  EXPECT_EQ(t["c"].steps_again(), 0U);
  EXPECT_EQ(t["a"].steps_again(), 0U);
}

TEST(FactorExchange, WithoutRelayingOnlyTheOwnStepsTravel) {
  ThreeAgents t(/*relay=*/false);
  for (std::uint32_t k = 1; k <= kMet; ++k) t.Run(k, Mutual("a", "b"));
  for (std::uint32_t k = kMet + 1; k <= 35; ++k) t.Run(k, k >= 30 ? Mutual("b", "c") : decltype(Mutual("b", "c")){});
  EXPECT_EQ(t["b"].Held("a"), kMet + kWindow);
  EXPECT_EQ(t["c"].Held("a"), 0U);
  EXPECT_EQ(t["c"].Held("b"), 35U);
}

TEST(FactorExchange, APeerThatHearsTheOriginItselfGetsNoRelayedCopies) {
  ThreeAgents t;
  const std::map<std::string, std::vector<std::string>> all = {{"a", {"b", "c"}}, {"b", {"a", "c"}}, {"c", {"a", "b"}}};
  for (std::uint32_t k = 1; k <= 40; ++k) {
    for (const auto& b : t.Run(k, all)) {
      for (const auto& run : b.runs) EXPECT_EQ(run.origin, b.header.sender) << "relayed at step " << k;
    }
  }
  EXPECT_EQ(t["c"].Held("a"), 40U);
  EXPECT_EQ(t["c"].steps_received(), 80U);
}

// a and b meet at every step and so do b and c; from step kBlind on a also sees c, which does
// not see a (a narrow field of view): c never sends a what it holds.
constexpr std::uint32_t kBlind = 30;

TEST(FactorExchange, WhatARobotThatDoesNotSendHoldsIsLearntFromThoseThatDo) {
  ThreeAgents t;
  std::uint32_t own_sent_to_c = 0;
  std::map<std::string, std::uint32_t> passed_at;  // by sender, recipient and robot
  for (std::uint32_t k = 1; k <= kBlind + 10; ++k) {
    std::map<std::string, std::vector<std::string>> sees = {{"a", {"b"}}, {"b", {"a", "c"}}, {"c", {"b"}}};
    if (k >= kBlind) sees["a"].push_back("c");
    for (const auto& b : t.Run(k, sees)) {
      if (b.header.sender == "a" && b.header.recipient == "c" && !b.runs.empty() && b.runs[0].origin == "a") {
        own_sent_to_c += static_cast<std::uint32_t>(b.runs[0].steps.size());
      }
      // What is heard of a robot is passed on to a peer at most every kHeardSteps steps.
      for (const auto& h : b.heard) {
        EXPECT_NE(h.robot, b.header.recipient);
        auto& last = passed_at[b.header.sender + b.header.recipient + h.robot];
        EXPECT_TRUE(last == 0 || k >= last + FactorExchange::kHeardSteps) << k;
        last = k;
      }
    }
  }
  // c had a's steps up to about kBlind from b; b told a what c holds, and a sent c only the
  // steps since (not all kBlind + 10 of them, as it would knowing nothing).
  EXPECT_EQ(passed_at.count("bac"), 1U) << "b passed on what it heard c hold to a";
  EXPECT_EQ(t["c"].Held("a"), kBlind + 10);
  EXPECT_LT(own_sent_to_c, 2 * FactorExchange::kRelayLagSteps);         // 40 knowing nothing
  EXPECT_LT(t["c"].steps_again(), 2 * FactorExchange::kRelayLagSteps);  // 66 knowing nothing
}

TEST(FactorExchange, ALostBatchIsMadeGood) {
  ThreeAgents t;
  for (std::uint32_t k = 1; k <= 4; ++k) t.Run(k, {});
  t.Run(5, Mutual("a", "b"));  // the greetings
  // a's first batch with steps is lost; the next ones start beyond what b holds (gaps) until b's
  // batches tell a what b holds, and a sends from there.
  t.Run(6, {}, [](const FactorBatch& b) { return b.header.sender == "a"; });
  EXPECT_EQ(t["b"].Held("a"), 0U);
  const std::uint32_t told = 6 + FactorExchange::kAckLagSteps + 1;  // b's batch of step 8 is heard
  for (std::uint32_t k = 7; k < told; ++k) t.Run(k, {});
  EXPECT_GT(t["b"].gaps(), 0);
  EXPECT_EQ(t["b"].Held("a"), 0U);
  t.Run(told, {});
  EXPECT_EQ(t["b"].Held("a"), told);
  // Once made good, only the new steps travel.
  for (const auto& b : t.Run(told + 1, {})) {
    if (b.header.sender == "a") {
      EXPECT_EQ(b.runs.at(0).steps.size(), 1U);
    }
  }
}

TEST(FactorExchange, AStepReachingAnAgentTwiceEntersOnce) {
  ThreeAgents t;
  // a meets b and c at once; then b and c meet: each has a's steps, and each sends them on only
  // if the other lacks them, and any that come twice are taken once.
  for (std::uint32_t k = 1; k <= 3; ++k) t.Run(k, {{"a", {"b", "c"}}, {"b", {"a"}}, {"c", {"a"}}});
  for (std::uint32_t k = 4; k <= 12; ++k) t.Run(k, Mutual("b", "c"));
  EXPECT_EQ(t["b"].Held("a"), 3U + kWindow);
  EXPECT_EQ(t["c"].Held("a"), 3U + kWindow);
  EXPECT_EQ(t["c"].steps_received(), t["c"].Held("a") + t["c"].Held("b"));
}

class RejectedBatch : public ::testing::Test {
 protected:
  // b's batch to a after step 8, having seen a at step 5 and had no word from a: its greetings
  // of steps 5 to 7, then its steps.
  void SetUp() override {
    for (std::uint32_t k = 1; k <= 8; ++k) {
      b_.RecordOwn(Step("b", k, k == 5 ? std::vector<std::string>{"a"} : std::vector<std::string>{}), {Track(k)});
      const auto out = b_.Outgoing(k, 0.1 * k);
      ASSERT_EQ(out.size(), k < 5 ? 0U : 1U) << "step " << k;
      if (k < 8) continue;
      good_ = out[0];
      ASSERT_EQ(good_.runs.size(), 1U);
      ASSERT_EQ(good_.runs[0].steps.size(), 8U);
    }
  }
  void ExpectRejected(const FactorBatch& batch) {
    FactorExchange a(Options("a"));
    EXPECT_FALSE(a.Receive(batch));
    EXPECT_EQ(a.Held("b"), 0U) << "a rejected batch leaves nothing";
  }
  FactorExchange b_{Options("b")};
  FactorBatch good_;
};

TEST_F(RejectedBatch, TheGoodOneIsTaken) {
  FactorExchange a(Options("a"));
  EXPECT_TRUE(a.Receive(good_));
  EXPECT_EQ(a.Held("b"), 8U);
}

TEST_F(RejectedBatch, NotOpenedByADetectionOfTheRecipient) {
  FactorBatch forged = good_;
  forged.runs[0].steps[4].lidar.robots.clear();
  ExpectRejected(forged);
  forged = good_;
  forged.opened_by_step = 3;  // step 3 saw nobody
  ExpectRejected(forged);
  forged = good_;
  forged.header.step = 5 + kWindow + 1;  // long after the detection
  ExpectRejected(forged);
}

TEST_F(RejectedBatch, OneWhoseOpeningStepIsMissingIsAGapNotARejection) {
  // What b sends after a lost batch: its steps from 6 on, the detection of step 5 not carried.
  FactorBatch later = good_;
  later.runs[0].first_step = 6;
  later.runs[0].steps = {Step("b", 6)};
  later.runs[0].tracks.clear();  // that of step 1, not carried
  later.header.step = 6;
  FactorExchange a(Options("a"));
  EXPECT_TRUE(a.Receive(later));
  EXPECT_EQ(a.gaps(), 1);
  EXPECT_EQ(a.Held("b"), 0U);
  // With the opening step carried apart, the detection is checked (and the run is a gap).
  later.opening = {good_.runs[0].steps[4]};
  EXPECT_TRUE(a.Receive(later));
  EXPECT_EQ(a.gaps(), 2);
  later.opening[0].lidar.robots.clear();
  EXPECT_FALSE(a.Receive(later));
}

TEST_F(RejectedBatch, Malformed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  FactorBatch bad = good_;
  bad.runs[0].steps[2].lidar.landmarks[0].range_m = nan;
  ExpectRejected(bad);
  bad = good_;
  bad.runs[0].steps[2].odometry.segments[0].v_mps = std::numeric_limits<double>::infinity();
  ExpectRejected(bad);
  bad = good_;
  bad.runs[0].steps[2].lidar.landmarks[0].landmark_id = -1;  // unlabelled
  ExpectRejected(bad);
  bad = good_;
  bad.runs[0].steps[2].lidar.stamp.step = 9;  // out of sequence
  ExpectRejected(bad);
  bad = good_;
  bad.runs[0].first_pose.heading = nan;
  ExpectRejected(bad);
  bad = good_;
  bad.runs[0].origin = "z";  // not of the team
  ExpectRejected(bad);
  bad = good_;
  bad.runs.push_back(bad.runs[0]);  // an origin twice
  ExpectRejected(bad);
  bad = good_;
  bad.runs[0].steps.resize(51, bad.runs[0].steps[0]);  // beyond max_batch_steps
  ExpectRejected(bad);
}

TEST_F(RejectedBatch, MalformedHoldingsPassedOn) {
  const FactorHolding of_c{"c", 3, "", 0};
  FactorBatch with = good_;
  with.heard = {{"c", 8, {of_c}}};
  FactorExchange a(Options("a"));
  EXPECT_TRUE(a.Receive(with)) << "well formed";
  const auto bad = [&](const std::vector<HeardHoldings>& heard) {
    FactorBatch b = good_;
    b.heard = heard;
    ExpectRejected(b);
  };
  bad({{"z", 8, {of_c}}});                            // not of the team
  bad({{"b", 8, {of_c}}});                            // the sender's own: in holdings
  bad({{"c", 9, {of_c}}});                            // of a step after the batch's
  bad({{"c", 0, {of_c}}});                            // of no step
  bad({{"c", 8, {of_c}}, {"c", 7, {of_c}}});          // a robot twice
  bad({{"c", 8, {{"z", 3, "", 0}}}});                 // an origin not of the team
  bad({{"c", 8, {of_c, of_c}}});                      // an origin twice
  bad({{"c", 8, {{"c", 3, "y", 2}}}});                // a feeder not of the team
  bad({{"a", 8, {of_c}}});                            // the recipient's own
  bad({{"c", 8, {{"c", 8 + kWindow + 1, "", 0}}}});   // more steps than there can be
  bad({{"c", 8, {{"c", 3, "a", 8 + kWindow + 1}}}});  // fed at a later step than there can be
  FactorBatch claims = good_;                         // nor in the sender's own holdings
  claims.holdings.push_back({"c", 8 + kWindow + 1, "", 0});
  ExpectRejected(claims);
  FactorExchange without(Options("a", false));  // with relaying off, nothing is passed on
  EXPECT_FALSE(without.Receive(with));
}

TEST_F(RejectedBatch, MalformedTrackEstimates) {
  ASSERT_FALSE(good_.runs[0].tracks.empty());
  const auto with = [&](auto change) {
    FactorBatch bad = good_;
    change(&bad.runs[0].tracks[0]);
    return bad;
  };
  ExpectRejected(with([](TrackEstimate* t) { t->mean.x() = std::numeric_limits<double>::quiet_NaN(); }));
  ExpectRejected(with([](TrackEstimate* t) { t->label = 0; }));
  ExpectRejected(with([](TrackEstimate* t) { t->step = 9; }));  // not a step of the run
  ExpectRejected(with([](TrackEstimate* t) { t->position_covariance(0, 0) = -1.0; }));
  ExpectRejected(with([](TrackEstimate* t) { t->heading_var = -0.1; }));
  ExpectRejected(with([](TrackEstimate* t) { t->w_radps = std::numeric_limits<double>::infinity(); }));
  ExpectRejected(with([](TrackEstimate* t) { t->mean.y() = 2e6; }));  // beyond kMaxTrackCoordinateM
  ExpectRejected(with([](TrackEstimate* t) { t->label = kMaxTrackLabel + 1; }));
  ExpectRejected(with([](TrackEstimate* t) { t->label = 8; }));  // no reading of its step names it
  FactorBatch twice = good_;
  twice.runs[0].tracks.push_back(twice.runs[0].tracks[0]);
  ExpectRejected(twice);
  FactorBatch many = good_;
  many.runs[0].tracks.resize(257, many.runs[0].tracks[0]);
  ExpectRejected(many);
}

TEST(FactorExchange, OnlyWellFormedEstimatesAreSharedAndARunCarriesAtMost256) {
  const auto long_runs = [](const std::string& id) {
    AgentOptions o = Options(id);
    o.cooperation.max_batch_steps = 500;
    return o;
  };
  FactorExchange a(long_runs("a"));
  TrackEstimate singular = Track(1);
  singular.position_covariance.setZero();
  a.RecordOwn(Step("a", 1), {singular});
  EXPECT_TRUE(a.logs().at("a").tracks.empty());
  TrackEstimate unnamed = Track(2);
  unnamed.label = 8;  // the step's reading is labelled 7
  a.RecordOwn(Step("a", 2), {unnamed});
  EXPECT_TRUE(a.logs().at("a").tracks.empty());
  // 300 steps, each reading a landmark of its own: one catch-up run to b carries the newest 256.
  for (std::uint32_t k = 3; k <= 300; ++k) {
    common::SensorStep s = Step("a", k, k == 300 ? std::vector<std::string>{"b"} : std::vector<std::string>{});
    s.lidar.landmarks[0].landmark_id = static_cast<int>(k);
    TrackEstimate t = Track(k);
    t.label = k;
    a.RecordOwn(s, {t});
  }
  EXPECT_EQ(a.logs().at("a").tracks.size(), 298U);
  for (std::uint32_t k = 300; k <= 303; ++k) {
    if (k > 300) a.RecordOwn(Step("a", k));
    for (const auto& batch : a.Outgoing(k, 0.1 * k)) {
      for (const auto& run : batch.runs) {
        if (run.steps.empty()) continue;
        EXPECT_EQ(run.tracks.size(), 256U);
        FactorExchange b(long_runs("b"));
        EXPECT_TRUE(b.Receive(batch));
        EXPECT_EQ(b.logs().at("a").tracks.size(), 256U);
        EXPECT_EQ(b.logs().at("a").tracks.begin()->first, 45U);  // the oldest 42 left for later
        return;
      }
    }
  }
  ADD_FAILURE() << "a sent no steps to b";
}

TEST_F(RejectedBatch, TheRecipientsOwnStepsOrRelayedOnesWhenRelayingIsOff) {
  FactorBatch own = good_;
  FactorRun mine{"a", 1, {}, {Step("a", 1)}, {}};
  own.runs.push_back(mine);
  ExpectRejected(own);
  FactorBatch relayed = good_;
  relayed.runs.push_back({"c", 1, {}, {Step("c", 1)}, {}});
  FactorExchange a(Options("a"));
  EXPECT_TRUE(a.Receive(relayed));
  EXPECT_EQ(a.Held("c"), 1U);
  FactorExchange no_relay(Options("a", /*relay=*/false));
  EXPECT_FALSE(no_relay.Receive(relayed));
}

TEST(FactorExchange, HeldBytesGrowByEachStepsContainers) {
  FactorExchange a(Options("a"));
  EXPECT_EQ(a.HeldBytes(), 0U);
  const std::size_t per_step =
      sizeof(common::SensorStep) + sizeof(common::LandmarkDetection) + sizeof(common::OdometrySegment);
  for (std::uint32_t k = 1; k <= 4; ++k) a.RecordOwn(Step("a", k));  // one segment, one reading each
  EXPECT_EQ(a.HeldBytes(), 4 * per_step);
  for (std::uint32_t k = 5; k <= 10; ++k) a.RecordOwn(Step("a", k));
  EXPECT_EQ(a.HeldBytes(), 10 * per_step);  // the steps since the last count added
  EXPECT_EQ(a.HeldBytes(), 10 * per_step);
  std::cout << "a held step of one segment and one reading: " << per_step << " bytes\n";
}

TEST(FactorExchange, ComesBackFromAnArchiveAsItWas) {
  ThreeAgents t;
  for (std::uint32_t k = 1; k <= 6; ++k) t.Run(k, Mutual("a", "b"));
  common::Archive out = common::Archive::ForWriting();
  t["b"].Io(out);
  FactorExchange back(Options("b"));
  common::Archive in = common::Archive::ForReading(out.bytes());
  back.Io(in);
  EXPECT_TRUE(in.AtEnd());
  EXPECT_EQ(back.Held("a"), 6U);
  EXPECT_EQ(back.Held("b"), 6U);
  EXPECT_EQ(back.HeldBytes(), t["b"].HeldBytes());
  // It goes on as the original does.
  t["b"].RecordOwn(Step("b", 7, {"a"}));
  back.RecordOwn(Step("b", 7, {"a"}));
  const auto x = t["b"].Outgoing(7, 0.7);
  const auto y = back.Outgoing(7, 0.7);
  ASSERT_EQ(x.size(), y.size());
  ASSERT_EQ(x.size(), 1U);
  EXPECT_EQ(x[0].runs.size(), y[0].runs.size());
  EXPECT_EQ(x[0].runs[0].first_step, y[0].runs[0].first_step);
}

}  // namespace
}  // namespace mrslam::robot_agent::cooperation
