#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "common/config/scenario_keys.h"
#include "tests/test_paths.h"

// docs/scenario-schema.md documents exactly the keys the parser reads: every table row whose
// first cell is a backticked key path names one key, and the parser's keys (looked up over every
// scenario in config/ and a scheduled robot that slips) are the same set.
namespace mrslam::common {
namespace {

namespace fs = std::filesystem;
using testing::SourcePath;

std::set<std::string> DocumentedKeys(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << "cannot open " << path;
  const std::regex row(R"(^\|\s*`([A-Za-z0-9_.\[\]]+)`\s*\|)");
  std::set<std::string> keys;
  std::smatch m;
  for (std::string line; std::getline(in, line);) {
    if (std::regex_search(line, m, row)) keys.insert(m[1]);
  }
  return keys;
}

std::vector<YAML::Node> ScenarioDocuments() {
  std::vector<YAML::Node> documents;
  for (const auto& entry : fs::directory_iterator(SourcePath("config"))) {
    if (entry.path().extension() == ".yaml") documents.push_back(YAML::LoadFile(entry.path().string()));
  }
  // No file in config/ drives a robot by a schedule or makes it slip: one more document does, for
  // the segments' and the slips' keys.
  YAML::Node schedule = YAML::LoadFile(SourcePath("tests/common/minimal_scenario.yaml"));
  schedule["robots"][0]["control"] = YAML::Load("{type: schedule, segments: [{v_mps: 0.5, duration_s: 1.0}]}");
  schedule["robots"][0]["slips"] = YAML::Load("[{step: 3, displacement: [1.0, 0.0, 0.5]}]");
  documents.push_back(schedule);
  return documents;
}

std::string Join(const std::set<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += "\n  " + k;
  return out;
}

TEST(ScenarioSchemaTest, TheDocumentedKeysAreTheParsersKeys) {
  const std::set<std::string> documented = DocumentedKeys(SourcePath("docs/scenario-schema.md"));
  const std::set<std::string> parsed = ScenarioKeys(ScenarioDocuments());
  ASSERT_GT(parsed.size(), 50u);  // the parser's schema is large; a small set means lookups were lost
  std::set<std::string> undocumented, unknown;
  for (const auto& k : parsed) {
    if (documented.count(k) == 0) undocumented.insert(k);
  }
  for (const auto& k : documented) {
    if (parsed.count(k) == 0) unknown.insert(k);
  }
  EXPECT_TRUE(undocumented.empty()) << "keys the parser reads that docs/scenario-schema.md lacks:"
                                    << Join(undocumented);
  EXPECT_TRUE(unknown.empty()) << "keys docs/scenario-schema.md documents that the parser does not read:"
                               << Join(unknown);
}

TEST(ScenarioSchemaTest, SequenceElementsAreWrittenAsBrackets) {
  const auto keys = ScenarioKeys({YAML::LoadFile(SourcePath("tests/common/minimal_scenario.yaml"))});
  EXPECT_EQ(keys.count("robots[].id"), 1u);
  EXPECT_EQ(keys.count("robots"), 0u);  // a mapping or sequence is not a leaf key
  EXPECT_EQ(keys.count("filter.particles"), 1u);
}

}  // namespace
}  // namespace mrslam::common
