#include "common/config/scenario_options.h"
#include "tests/test_paths.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

namespace mrslam::common {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::string SourceDir() { return mrslam::testing::SourcePath("."); }

// Every *.yaml file in a folder of the source tree, sorted.
std::vector<std::string> YamlFiles(const std::string& folder) {
  std::vector<std::string> files;
  const fs::path dir = fs::path(SourceDir()) / folder;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = fs::path(info.param).stem().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

// The message of the ScenarioError that loading throws, or "" if nothing (or something else) is
// thrown.
std::string LoadError(const std::string& path, const std::vector<std::string>& overrides = {}) {
  try {
    LoadScenario(path, overrides);
  } catch (const ScenarioError& e) {
    return e.what();
  }
  return "";
}

// --- every scenario in config/ loads (cartographer_ros configuration_files_test.cc) ---

class ConfigFileTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ConfigFileTest, LoadsAndValidates) {
  ScenarioOptions options;
  ASSERT_NO_THROW(options = LoadScenario(GetParam(), {})) << LoadError(GetParam());
  EXPECT_FALSE(options.name.empty());
  EXPECT_FALSE(options.robots.empty());
  std::string error;
  EXPECT_TRUE(options.IsValid(&error)) << error;
}

INSTANTIATE_TEST_SUITE_P(Config, ConfigFileTest, ::testing::ValuesIn(YamlFiles("config")), TestName);

TEST(ConfigFileTest, ThereAreScenarios) { EXPECT_GE(YamlFiles("config").size(), 1u); }

// --- malformed scenarios are rejected, naming the key ---

// The key a bad scenario must be rejected for, from its first line "# expect: <key>".
std::string ExpectedKey(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  const std::string tag = "# expect: ";
  return line.rfind(tag, 0) == 0 ? line.substr(tag.size()) : "";
}

class BadScenarioTest : public ::testing::TestWithParam<std::string> {};

TEST_P(BadScenarioTest, IsRejectedNamingTheKey) {
  const std::string key = ExpectedKey(GetParam());
  ASSERT_FALSE(key.empty()) << GetParam() << " must start with '# expect: <key>'";
  const std::string error = LoadError(GetParam());
  ASSERT_FALSE(error.empty()) << GetParam() << " was accepted";
  EXPECT_THAT(error, HasSubstr("'" + key + "'"));
}

INSTANTIATE_TEST_SUITE_P(Bad, BadScenarioTest, ::testing::ValuesIn(YamlFiles("tests/common/bad_scenarios")), TestName);

TEST(BadScenarioTest, CoverAtLeastTwelveFaults) { EXPECT_GE(YamlFiles("tests/common/bad_scenarios").size(), 12u); }

TEST(ParseScenarioTest, ParsesTextAndRejectsAnyBadTextWithAScenarioError) {
  std::ifstream in(SourceDir() + "/tests/common/minimal_scenario.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(ParseScenario(text).robots.size(), 2U);
  EXPECT_THROW(ParseScenario("{[a]: 1}"), ScenarioError);  // a list as a key
  EXPECT_THROW(ParseScenario("name: [unclosed"), ScenarioError);
  EXPECT_THROW(ParseScenario(""), ScenarioError);
}

// Each bad file is this one with one fault, so the fault is what gets rejected.
TEST(BadScenarioTest, TheirBaseIsValid) {
  const std::string path = SourceDir() + "/tests/common/minimal_scenario.yaml";
  EXPECT_EQ(LoadError(path), "");
}

// Writes text to a file in the test's temporary folder and returns its path.
std::string TempFile(const std::string& name, const std::string& text) {
  std::string path = ::testing::TempDir() + "/mrslam_scenario_test_" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(ScenarioErrorTest, UnreadableAndNonMappingFilesAreErrors) {
  EXPECT_THAT(LoadError(SourceDir() + "/tests/common/no_such_file.yaml"), HasSubstr("cannot open"));
  EXPECT_THAT(LoadError(TempFile("empty.yaml", "")), HasSubstr("must be a YAML mapping"));
  EXPECT_THAT(LoadError(TempFile("list.yaml", "- a\n- b\n")), HasSubstr("must be a YAML mapping"));
  EXPECT_THAT(LoadError(TempFile("broken.yaml", "name: [unclosed\n")), HasSubstr("not valid YAML"));
}

// --- overrides (--set key.path=value) ---

std::string Minimal() { return SourceDir() + "/tests/common/minimal_scenario.yaml"; }

TEST(ApplyOverrideTest, SetsNestedKeysAndListElements) {
  const auto o = LoadScenario(
      Minimal(), {"robots.1.control.v_mps=2", "run.steps=5", "sensors.lidar.report_identity=true", "seed=42"});
  EXPECT_EQ(o.robots[1].control.v_mps, 2.0);
  EXPECT_EQ(o.robots[0].control.v_mps, 0.5);
  EXPECT_EQ(o.run.steps, 5);
  EXPECT_TRUE(o.sensors.lidar.report_identity);
  EXPECT_EQ(o.seed, 42u);
}

TEST(ApplyOverrideTest, LaterOverridesWin) {
  EXPECT_EQ(LoadScenario(Minimal(), {"run.steps=5", "run.steps=7"}).run.steps, 7);
}

TEST(ApplyOverrideTest, AddsAnAbsentSection) {
  const auto o = LoadScenario(Minimal(), {"noise.robot_process_var=[0.1, 0.2, 0.3]"});
  EXPECT_EQ(o.noise.robot_process_var.y(), 0.2);
}

TEST(ApplyOverrideTest, WorksOnEveryConfigFile) {
  for (const auto& file : YamlFiles("config")) {
    SCOPED_TRACE(file);
    const auto o = LoadScenario(file, {"robots.0.control.v_mps=2", "run.steps=5"});
    EXPECT_EQ(o.run.steps, 5);
    EXPECT_EQ(o.robots[0].control.v_mps, 2.0);
  }
}

TEST(ApplyOverrideTest, RejectsBadPathsAndValues) {
  EXPECT_THAT(LoadError(Minimal(), {"robots.7.id=r9"}), HasSubstr("out of range"));
  EXPECT_THAT(LoadError(Minimal(), {"robots.first.id=r9"}), HasSubstr("must be an index"));
  EXPECT_THAT(LoadError(Minimal(), {"robots.2=x"}), HasSubstr("out of range"));
  EXPECT_THAT(LoadError(Minimal(), {"run.steps"}), HasSubstr("key.path=value"));
  EXPECT_THAT(LoadError(Minimal(), {"=5"}), HasSubstr("key.path=value"));
  EXPECT_THAT(LoadError(Minimal(), {"run.steps=[1, 2"}), HasSubstr("not valid YAML"));
  // A path through a scalar leads nowhere.
  EXPECT_THAT(LoadError(Minimal(), {"run.steps.x=1"}), HasSubstr("'run.steps' is a value"));
  EXPECT_THAT(LoadError(Minimal(), {"name.x.y=1"}), HasSubstr("'name' is a value"));
  // Overrides are checked like the file: unknown keys, types and ranges name the key.
  EXPECT_THAT(LoadError(Minimal(), {"run.stepz=5"}), HasSubstr("'run.stepz' is unknown"));
  EXPECT_THAT(LoadError(Minimal(), {"run.steps=0"}), HasSubstr("'run.steps'"));
  EXPECT_THAT(LoadError(Minimal(), {"run.steps=many"}), HasSubstr("'run.steps'"));
  EXPECT_THAT(LoadError(Minimal(), {"robots.1.id=r1"}), HasSubstr("'robots.1.id'"));
}

TEST(ApplyOverrideTest, EditsADocumentInPlace) {
  YAML::Node root = YAML::Load("run: {steps: 3}\nrobots: [{id: a}, {id: b}]");
  ApplyOverride(root, "robots.1.id=c");
  ApplyOverride(root, "run.dt_s=0.5");
  EXPECT_EQ(root["robots"][1]["id"].as<std::string>(), "c");
  EXPECT_EQ(root["robots"][0]["id"].as<std::string>(), "a");
  EXPECT_EQ(root["run"]["dt_s"].as<double>(), 0.5);
  EXPECT_EQ(root["run"]["steps"].as<int>(), 3);
  EXPECT_THROW(ApplyOverride(root, "robots.5.id=x"), ScenarioError);
}

// ---------------------------------------------------------------------------------------------
// The cooperation section.

TEST(CooperationOptions, ParsesDefaultsAndRejectsUnknownKeys) {
  const char* base = "name: t\nrun: {steps: 10, dt_s: 0.1}\nrobots: [{id: r1, pose: [0, 0, 0]}]\n";
  ScenarioOptions o = CreateScenarioOptions(YAML::Load(base));
  EXPECT_EQ(o.cooperation.map_fusion, robot_agent::MapFusionRule::kCovarianceIntersection);
  EXPECT_TRUE(o.cooperation.merge_maps);
  EXPECT_EQ(o.cooperation.max_snapshot_landmarks, 256);
  EXPECT_EQ(o.cooperation.min_seen_span_steps, 6);
  EXPECT_EQ(o.cooperation.merge_min_separation_m, 1.5);
  o = CreateScenarioOptions(YAML::Load(std::string(base) +
                                       "cooperation: {map_fusion: average, merge_maps: false, "
                                       "max_snapshot_landmarks: 10, cooperative_localization: true, "
                                       "min_seen_span_steps: 0, merge_min_separation_m: 0}\n"));
  EXPECT_EQ(o.cooperation.map_fusion, robot_agent::MapFusionRule::kAverage);
  EXPECT_FALSE(o.cooperation.merge_maps);
  EXPECT_EQ(o.cooperation.max_snapshot_landmarks, 10);
  EXPECT_TRUE(o.cooperation.cooperative_localization);
  EXPECT_EQ(o.cooperation.min_seen_span_steps, 0);
  EXPECT_EQ(o.cooperation.merge_min_separation_m, 0.0);
  EXPECT_THROW(CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {fusion: x}\n")), ScenarioError);
  EXPECT_THROW(CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {map_fusion: x}\n")), ScenarioError);
  o = CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {max_snapshot_landmarks: 0}\n"));
  std::string error;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("cooperation.max_snapshot_landmarks"), std::string::npos);
  o = CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {min_seen_span_steps: -1}\n"));
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("cooperation.min_seen_span_steps"), std::string::npos);
  o = CreateScenarioOptions(YAML::Load(std::string(base) + "cooperation: {merge_min_separation_m: -1}\n"));
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("cooperation.merge_min_separation_m"), std::string::npos);
  o = CreateScenarioOptions(YAML::Load(std::string(base) + "filter: {max_landmark_position_sd_m: .inf}\n"));
  EXPECT_TRUE(std::isinf(o.filter.max_landmark_position_sd_m));
  EXPECT_TRUE(o.IsValid(&error));
  o = CreateScenarioOptions(YAML::Load(std::string(base) + "filter: {max_landmark_position_sd_m: 0}\n"));
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("filter.max_landmark_position_sd_m"), std::string::npos);
}

}  // namespace
}  // namespace mrslam::common
