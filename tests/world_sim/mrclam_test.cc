// The MRCLAM reader and replay: the committed excerpt (always), broken copies of it, the real
// Dataset 6 when ../shared is beside the project (skipped otherwise), and the scenario's replay
// section.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/config/agent_options_projection.h"
#include "common/config/scenario_options.h"
#include "robot_agent/factory/filter_factory.h"
#include "robot_agent/filters/slam_filter.h"
#include "tests/test_paths.h"
#include "world_sim/replay/mrclam_reader.h"
#include "world_sim/replay/mrclam_replay.h"
#include "world_sim/source/step_source_factory.h"

namespace mrslam::world_sim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string SourceDir() { return mrslam::testing::SourcePath("."); }
std::string ExcerptDir() { return SourceDir() + "/tests/world_sim/data/mrclam_excerpt"; }
std::string Dataset6Dir() { return SourceDir() + "/../shared/data/mrclam/MRCLAM_Dataset6"; }

// A fresh copy of the excerpt in a temporary folder, to break.
std::string CopyOfExcerpt(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("mrclam-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const auto& e : fs::directory_iterator(ExcerptDir())) fs::copy_file(e.path(), dir / e.path().filename());
  return dir.string();
}

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A replay scenario over `dir` with the given robots.
common::ScenarioOptions ReplayScenario(const std::string& dir, const std::vector<std::string>& robots,
                                       double duration_s, double start_s = 0.0) {
  common::ScenarioOptions o;
  o.name = "mrclam_test";
  o.replay.enabled = true;
  o.replay.dir = dir;
  o.replay.step_s = 0.1;
  o.replay.start_s = start_s;
  o.replay.duration_s = duration_s;
  o.run.dt_s = 0.1;
  o.run.steps = static_cast<int>(std::lround(duration_s / 0.1));
  for (const auto& id : robots) {
    common::RobotOptions r;
    r.id = id;
    o.robots.push_back(r);
  }
  return o;
}

// Checks what every replay step must satisfy: odometry segments tile the step's interval,
// detections lie in it and come in time order.
void ExpectWellFormedStep(const std::vector<common::SensorStep>& samples, double step_start_s, double step_s) {
  for (const auto& s : samples) {
    double t = step_start_s;
    for (const auto& seg : s.odometry.segments) {
      EXPECT_NEAR(seg.time_s, t, 1e-6) << s.odometry.stamp.robot_id << " step " << s.odometry.stamp.step;
      EXPECT_GT(seg.dt_s, 0.0);
      t = seg.time_s + seg.dt_s;
    }
    EXPECT_NEAR(t, step_start_s + step_s, 1e-6);
    double last = step_start_s - 1e-6;
    for (const auto& d : s.lidar.landmarks) {
      EXPECT_GE(d.time_s, last);
      EXPECT_LT(d.time_s, step_start_s + step_s + 1e-6);
      last = d.time_s;
    }
    EXPECT_TRUE(s.imu.readings.empty());
  }
}

TEST(MrclamReaderTest, ReadsTheExcerpt) {
  const MrclamDataset d = ReadMrclamDataset(ExcerptDir(), {1, 2});
  EXPECT_THAT(d.problems, ::testing::IsEmpty());
  ASSERT_EQ(d.subject_of_barcode.size(), 20u);
  EXPECT_EQ(d.subject_of_barcode.at(5), 1);
  EXPECT_EQ(d.subject_of_barcode.at(14), 2);
  EXPECT_EQ(d.subject_of_barcode.at(63), 6);
  ASSERT_EQ(d.landmarks.size(), 15u);
  EXPECT_EQ(d.landmarks.front().subject, 6);
  EXPECT_DOUBLE_EQ(d.landmarks.front().x_m, 0.58831396);
  EXPECT_DOUBLE_EQ(d.landmarks.front().y_m, -4.28264845);
  const MrclamRobot& r1 = d.robots.at(1);
  EXPECT_EQ(r1.groundtruth.size(), 162u);
  EXPECT_EQ(r1.odometry.size(), 474u);
  ASSERT_EQ(r1.measurements.size(), 58u);
  EXPECT_DOUBLE_EQ(r1.measurements[0].time_s, 1248444189.599);
  EXPECT_EQ(r1.measurements[0].barcode, 14);
  EXPECT_DOUBLE_EQ(r1.measurements[0].range_m, 3.787);
  EXPECT_DOUBLE_EQ(r1.measurements[0].bearing_rad, -0.257);
  // Several rows per time stamp keep their order.
  EXPECT_DOUBLE_EQ(r1.measurements[1].time_s, 1248444189.599);
  EXPECT_EQ(r1.measurements[1].barcode, 90);
  EXPECT_DOUBLE_EQ(r1.odometry[0].v_mps, 0.086);
  EXPECT_DOUBLE_EQ(r1.odometry[0].w_radps, -0.398);
  EXPECT_DOUBLE_EQ(r1.groundtruth[0].pose.x, 1.41277290);
  EXPECT_DOUBLE_EQ(d.start_time_s, 1248444175.103);
  EXPECT_EQ(d.robots.at(2).measurements.size(), 30u);
}

TEST(MrclamReaderTest, MalformedRowsAreReportedWithFileAndLineAndSkipped) {
  const std::string dir = CopyOfExcerpt("malformed");
  const std::string path = dir + "/Robot1_Odometry.dat";
  // CRLF endings, trailing blanks and tabs, a blank line, a comment, a row with a word, a short
  // row and a row with an extra column.
  WriteFile(path,
            "# header\r\n# Time [s] v w\r\n"
            "100.0 \t 0.1 \t 0.2 \r\n"   // line 3
            "100.1\t0.1\t0.2\t\t  \r\n"  // line 4
            "\r\n"                       // line 5
            "  # a comment\r\n"          // line 6
            "100.2 \t abc \t 0.2\r\n"    // line 7: malformed
            "100.3 0.1\r\n"              // line 8: malformed
            "100.4 0.1 0.2 0.3\r\n"      // line 9: malformed
            "100.5 0.3 0.4");            // line 10, no line ending
  const MrclamTable t = ReadMrclamTable(path, 3);
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_DOUBLE_EQ(t.rows[1][0], 100.1);
  EXPECT_DOUBLE_EQ(t.rows[2][2], 0.4);
  ASSERT_EQ(t.problems.size(), 3u);
  EXPECT_THAT(t.problems[0], HasSubstr(path + ":7: 'abc' is not a number"));
  EXPECT_THAT(t.problems[1], HasSubstr(path + ":8: expected 3 numbers, got 2"));
  EXPECT_THAT(t.problems[2], HasSubstr(path + ":9: expected 3 numbers, got 4"));
  // The data set keeps reading and lists the problems; the replay still runs.
  const MrclamDataset d = ReadMrclamDataset(dir, {1});
  EXPECT_EQ(d.problems.size(), 3u);
  EXPECT_EQ(d.robots.at(1).odometry.size(), 3u);
  fs::remove_all(dir);
}

TEST(MrclamReaderTest, LfEndingsAndUnsortedRowsReadAlike) {
  const std::string dir = CopyOfExcerpt("lf");
  WriteFile(dir + "/Robot1_Measurement.dat", "# x\n200.5 14 3.0 0.1\n200.1 90 2.0 -0.1\n200.1 61 2.5 0.0\n");
  const MrclamDataset d = ReadMrclamDataset(dir, {1});
  const auto& m = d.robots.at(1).measurements;
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].barcode, 90);  // sorted by time, ties in file order
  EXPECT_EQ(m[1].barcode, 61);
  EXPECT_EQ(m[2].barcode, 14);
  fs::remove_all(dir);
}

TEST(MrclamReaderTest, MissingFileIsAOneLineError) {
  const std::string dir = CopyOfExcerpt("missing");
  fs::remove(dir + "/Robot2_Odometry.dat");
  try {
    ReadMrclamDataset(dir, {1, 2});
    FAIL() << "expected MrclamError";
  } catch (const MrclamError& e) {
    const std::string what = e.what();
    EXPECT_THAT(what, HasSubstr("Robot2_Odometry.dat"));
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_THROW(ReadMrclamDataset(dir + "/nowhere", {1}), MrclamError);
  fs::remove_all(dir);
}

TEST(MrclamReaderTest, InterpolatesPosesAcrossTheAngleWrap) {
  const std::vector<MrclamPose> gt = {{10.0, {0.0, 0.0, 3.0}}, {11.0, {1.0, 2.0, -3.0}}};
  const common::Pose2 mid = InterpolatePose(gt, 10.5);
  EXPECT_NEAR(mid.x, 0.5, 1e-12);
  EXPECT_NEAR(mid.y, 1.0, 1e-12);
  EXPECT_NEAR(std::abs(mid.heading), common::kPi, 1e-9);  // through pi, not through 0
  EXPECT_DOUBLE_EQ(InterpolatePose(gt, 5.0).x, 0.0);      // held before the first
  EXPECT_DOUBLE_EQ(InterpolatePose(gt, 50.0).x, 1.0);     // and after the last
}

// A tiny synthetic data set: every rule of the stepping, checked by hand.
TEST(MrclamReplayTest, StepsCommandsAndMeasurementsByTheirTimeStamps) {
  const std::string dir = CopyOfExcerpt("synthetic");
  // t0 = 1000.0 (earliest ground truth of the replayed robots).
  WriteFile(dir + "/Robot1_Groundtruth.dat", "# gt\r\n1000.0 1.0 2.0 0.5\r\n1010.0 11.0 2.0 0.5\r\n");
  WriteFile(dir + "/Robot2_Groundtruth.dat", "# gt\r\n1000.5 0.0 0.0 0.0\r\n1010.0 0.0 0.0 0.0\r\n");
  WriteFile(dir + "/Robot1_Odometry.dat", "# odo\r\n1000.05 1.0 0.1\r\n1000.13 2.0 0.2\r\n");
  WriteFile(dir + "/Robot2_Odometry.dat", "# odo\r\n");
  // Barcode 14 = robot 2, 41 = robot 3 (not replayed), 63 = landmark 6, 99 unknown.
  WriteFile(dir + "/Robot1_Measurement.dat",
            "# m\r\n1000.02 63 2.0 0.1\r\n1000.02 14 3.0 -0.1\r\n1000.09 99 1.0 0.0\r\n"
            "1000.15 41 4.0 0.2\r\n1000.15 63 2.1 0.1\r\n");
  WriteFile(dir + "/Robot2_Measurement.dat", "# m\r\n");
  MrclamReplay replay(ReplayScenario(dir, {"r1", "r2"}, 1.0));

  // Step 0: each robot's frame is its first pose, so the truth in its own frame is the origin.
  const common::GroundTruth t0 = replay.Truth();
  ASSERT_EQ(t0.frames.size(), 2u);
  EXPECT_DOUBLE_EQ(t0.frames[0].second.x, 1.0);
  EXPECT_DOUBLE_EQ(t0.frames[0].second.heading, 0.5);
  EXPECT_EQ(t0.landmarks.size(), 15u);
  EXPECT_EQ(t0.landmarks.front().id, "6");

  const auto s1 = replay.Step();
  ASSERT_EQ(s1.size(), 2u);
  ExpectWellFormedStep(s1, 0.0, 0.1);
  EXPECT_EQ(s1[0].lidar.stamp.step, 1u);
  EXPECT_NEAR(s1[0].lidar.stamp.time_s, 0.1, 1e-12);
  const auto& seg = s1[0].odometry.segments;
  ASSERT_EQ(seg.size(), 2u);
  EXPECT_DOUBLE_EQ(seg[0].v_mps, 0.0);  // standing still before the first command
  EXPECT_NEAR(seg[0].dt_s, 0.05, 1e-9);
  EXPECT_DOUBLE_EQ(seg[1].v_mps, 1.0);
  ASSERT_EQ(s1[0].lidar.landmarks.size(), 1u);
  EXPECT_EQ(s1[0].lidar.landmarks[0].landmark_id, 6);
  EXPECT_NEAR(s1[0].lidar.landmarks[0].time_s, 0.02, 1e-9);
  ASSERT_EQ(s1[0].lidar.robots.size(), 1u);
  EXPECT_EQ(s1[0].lidar.robots[0].seen_robot_id, "r2");
  EXPECT_DOUBLE_EQ(s1[0].lidar.robots[0].range_m, 3.0);
  EXPECT_EQ(replay.stats().unknown_barcodes, 1);

  const auto s2 = replay.Step();
  ExpectWellFormedStep(s2, 0.1, 0.1);
  const auto& seg2 = s2[0].odometry.segments;
  ASSERT_EQ(seg2.size(), 2u);
  EXPECT_DOUBLE_EQ(seg2[0].v_mps, 1.0);
  EXPECT_NEAR(seg2[0].dt_s, 0.03, 1e-9);
  EXPECT_DOUBLE_EQ(seg2[1].v_mps, 2.0);
  EXPECT_DOUBLE_EQ(seg2[1].w_radps, 0.2);
  EXPECT_EQ(s2[0].lidar.landmarks.size(), 1u);
  EXPECT_TRUE(s2[0].lidar.robots.empty());
  EXPECT_EQ(replay.stats().robots_not_replayed, 1);
  // Truth interpolated at the step's end: robot 1 moves 1 m/s along x.
  EXPECT_NEAR(replay.Truth().robots[0].pose.x, 1.2, 1e-9);
  fs::remove_all(dir);
}

TEST(MrclamReplayTest, WindowAndSubsetOfTheExcerpt) {
  // Robot 1 only, 14-20 s (the excerpt ends at 19.9 s): robot 1's detections of other robots are
  // dropped and counted.
  auto options = ReplayScenario(ExcerptDir(), {"r1"}, 6.0, 14.0);
  MrclamReplay replay(options);
  int landmarks = 0;
  for (int k = 0; k < 60; ++k) {
    const auto s = replay.Step();
    ASSERT_EQ(s.size(), 1u);
    ExpectWellFormedStep(s, 14.0 + 0.1 * k, 0.1);
    landmarks += static_cast<int>(s[0].lidar.landmarks.size());
    EXPECT_TRUE(s[0].lidar.robots.empty());
  }
  EXPECT_EQ(landmarks + replay.stats().robots_not_replayed + replay.stats().unknown_barcodes, 58);
  EXPECT_EQ(replay.stats().robots_not_replayed, 20);  // of r2..r5
  EXPECT_NEAR(replay.time_s(), 20.0, 1e-9);
}

TEST(MrclamReplayTest, StepSourceIsTheReplayWhenTheScenarioHasOne) {
  const auto options = ReplayScenario(ExcerptDir(), {"r1", "r2"}, 1.0);
  const std::unique_ptr<StepSource> replay = MakeStepSource(options);
  ASSERT_NE(dynamic_cast<const MrclamReplay*>(replay.get()), nullptr);
  EXPECT_EQ(replay->Truth().frames.size(), 2u);

  common::ScenarioOptions simulated = options;
  simulated.replay.enabled = false;
  const std::unique_ptr<StepSource> world = MakeStepSource(simulated);
  EXPECT_EQ(dynamic_cast<const MrclamReplay*>(world.get()), nullptr);
  EXPECT_EQ(world->Step().size(), 2u);
}

TEST(MrclamReplayTest, ScenarioReplaySectionDerivesTheRunAndResolvesTheFolder) {
  const fs::path dir = fs::temp_directory_path() / ("mrclam-scn-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "s.yaml").string();
  WriteFile(path,
            "name: s\nreplay: {dir: data/set, duration_s: 60, robots: [r1, r3]}\n"
            "robots: [{id: r1}, {id: r2}, {id: r3}]\n");
  const auto o = common::LoadScenario(path, {});
  EXPECT_TRUE(o.replay.enabled);
  EXPECT_EQ(o.replay.dir, dir.string() + "/data/set");
  EXPECT_EQ(o.run.steps, 600);
  EXPECT_DOUBLE_EQ(o.run.dt_s, 0.1);
  ASSERT_EQ(o.robots.size(), 2u);
  EXPECT_EQ(o.robots[1].id, "r3");
  // An override is relative to the current directory.
  EXPECT_EQ(common::LoadScenario(path, {"replay.dir=other"}).replay.dir, "other");
  EXPECT_EQ(common::LoadScenario(path, {"run.steps=10"}).run.steps, 10);
  const auto error = [&](const std::vector<std::string>& overrides) {
    try {
      common::LoadScenario(path, overrides);
    } catch (const common::ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error({"run.steps=601"}), HasSubstr("run.steps"));
  EXPECT_THAT(error({"run.dt_s=0.2"}), HasSubstr("run.dt_s"));
  EXPECT_THAT(error({"replay.speed=2"}), HasSubstr("'replay.speed' is unknown"));
  EXPECT_THAT(error({"replay.robots=[r9]"}), HasSubstr("replay.robots.0"));
  EXPECT_THAT(error({"replay.step_s=-1"}), HasSubstr("replay.step_s"));
  EXPECT_THAT(error({"robots.0.id=robot1", "replay.robots=[robot1]"}), HasSubstr("r<n>"));
  fs::remove_all(dir);
}

TEST(MrclamReplayTest, ConfigFilePointsAtDataset6) {
  const auto o = common::LoadScenario(SourceDir() + "/config/mrclam.yaml", {});
  EXPECT_TRUE(o.replay.enabled);
  EXPECT_THAT(o.replay.dir, HasSubstr("shared/data/mrclam/MRCLAM_Dataset6"));
  EXPECT_EQ(o.robots.size(), 5u);
  EXPECT_EQ(o.run.steps, 9000);
}

// The agents' calibration for real odometry (filter.odometry_scale, odometry_turn_scale,
// odometry_lag_s): commands of 1 m/s and 1 rad/s for 0.5 s move a noiseless filter 0.2 s later
// at 0.9 times the speed and 0.8 times the turn rate.
TEST(MrclamCalibrationTest, FastSlamDelaysAndScalesTheCommands) {
  common::ScenarioOptions o = ReplayScenario(ExcerptDir(), {"r1"}, 1.0);
  o.filter.particles = 1;
  o.filter.proposal = robot_agent::Proposal::kMotion;
  o.noise.robot_process_var.setZero();
  o.filter.odometry_scale = 0.9;
  o.filter.odometry_turn_scale = 0.8;
  o.filter.odometry_lag_s = 0.2;
  const auto filter = robot_agent::factory::CreateFilter(common::AgentOptionsFor(o, "r1"), 1);
  ASSERT_NE(filter, nullptr);
  std::vector<double> x;
  double heading = 0.0;
  for (int k = 1; k <= 10; ++k) {
    common::SensorStep step;
    const common::Stamp stamp{"r1", static_cast<std::uint32_t>(k), 0.1 * k};
    step.lidar.stamp = stamp;
    step.imu.stamp = stamp;
    step.odometry.stamp = stamp;
    const double v = k <= 5 ? 1.0 : 0.0;
    step.odometry.segments.push_back({0.1 * (k - 1), 0.05, v, v});
    step.odometry.segments.push_back({0.1 * (k - 1) + 0.05, 0.05, v, v});
    filter->Process(step);
    x.push_back(filter->Estimate().pose.x);
    heading = filter->Estimate().pose.heading;
  }
  EXPECT_NEAR(x[1], 0.0, 1e-9);  // nothing moves in the first 0.2 s
  EXPECT_GT(x[2], 0.0);
  EXPECT_NEAR(heading, 0.8 * 0.5, 1e-9);  // all of the turn, scaled
  EXPECT_NEAR(x[9], x[8], 1e-12);         // and then standing still
  // An arc of 0.9 * 0.5 m turning 0.4 rad: chord 2 (s / th) sin(th / 2), at th / 2 from x
  // (within the discretization of 0.05 s segments).
  const double chord = 2.0 * (0.45 / 0.4) * std::sin(0.2);
  EXPECT_NEAR(x[9], chord * std::cos(0.2), 0.01);
}

// The real Dataset 6: counts as the data set's own documentation gives them.
class Dataset6Test : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(Dataset6Dir())) GTEST_SKIP() << "no MRCLAM Dataset 6 at " << Dataset6Dir();
  }
};

TEST_F(Dataset6Test, ParsesEveryFileWithoutProblems) {
  const MrclamDataset d = ReadMrclamDataset(Dataset6Dir(), {1, 2, 3, 4, 5});
  EXPECT_THAT(d.problems, ::testing::IsEmpty());
  EXPECT_EQ(d.subject_of_barcode.size(), 20u);
  EXPECT_EQ(d.landmarks.size(), 15u);
  const std::map<int, std::size_t> gt_rows = {{1, 49241}, {2, 59705}, {3, 56977}, {4, 61714}, {5, 57467}};
  std::size_t measurements = 0;
  for (const auto& [subject, robot] : d.robots) {
    EXPECT_EQ(robot.groundtruth.size(), gt_rows.at(subject)) << subject;
    measurements += robot.measurements.size();
  }
  EXPECT_EQ(measurements, 19377u);
  EXPECT_DOUBLE_EQ(d.start_time_s, 1248444175.103);
  // Robot1's ground truth ends at 771.9 s.
  EXPECT_NEAR(d.robots.at(1).groundtruth.back().time_s - d.start_time_s, 771.9, 0.05);
}

TEST_F(Dataset6Test, FullReplayPublishesEveryMeasurementOnce) {
  const auto scenario = common::LoadScenario(SourceDir() + "/config/mrclam.yaml", {});
  MrclamReplay replay(scenario);
  int landmarks = 0, robots = 0;
  std::set<std::string> seen_pairs;
  for (int k = 0; k < scenario.run.steps; ++k) {
    const auto samples = replay.Step();
    if (k % 97 == 0) ExpectWellFormedStep(samples, 0.1 * k, 0.1);
    for (const auto& s : samples) {
      landmarks += static_cast<int>(s.lidar.landmarks.size());
      robots += static_cast<int>(s.lidar.robots.size());
      for (const auto& d : s.lidar.robots) seen_pairs.insert(s.lidar.stamp.robot_id + d.seen_robot_id);
      for (const auto& d : s.lidar.landmarks) {
        EXPECT_GE(d.landmark_id, 6);
        EXPECT_LE(d.landmark_id, 20);
      }
    }
  }
  EXPECT_EQ(landmarks, 15383);
  EXPECT_EQ(robots, 3988);
  EXPECT_EQ(replay.stats().unknown_barcodes, 6);
  EXPECT_EQ(seen_pairs.size(), 20u);  // every ordered pair of robots
  EXPECT_NEAR(replay.time_s(), 900.0, 1e-6);
}

TEST_F(Dataset6Test, MeasurementsAgreeWithTheInterpolatedTruth) {
  // The median range error against the interpolated ground truth is about 0.085 m (measured on the data):
  // checks the barcode mapping, the landmark ids and the time base together.
  MrclamReplay replay(ReplayScenario(Dataset6Dir(), {"r1", "r2", "r3", "r4", "r5"}, 120.0));
  std::map<std::string, common::Pose2> landmarks;
  for (const auto& l : replay.Truth().landmarks) landmarks[l.id] = l.pose;
  std::vector<double> range_errors;
  for (int k = 0; k < 1200; ++k) {
    const auto samples = replay.Step();
    const auto truth = replay.Truth();
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const common::Pose2& robot = truth.robots[i].pose;
      for (const auto& d : samples[i].lidar.landmarks) {
        const common::Pose2& l = landmarks.at(std::to_string(d.landmark_id));
        range_errors.push_back(std::abs(std::hypot(l.x - robot.x, l.y - robot.y) - d.range_m));
      }
    }
  }
  ASSERT_GT(range_errors.size(), 500u);
  std::nth_element(range_errors.begin(), range_errors.begin() + range_errors.size() / 2, range_errors.end());
  EXPECT_LT(range_errors[range_errors.size() / 2], 0.15);
}

}  // namespace
}  // namespace mrslam::world_sim
