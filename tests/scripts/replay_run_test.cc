#include "scripts/view/replay_run.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace mrslam::view {
namespace {

using ::testing::HasSubstr;

class ReplayRunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("mrslam-replay-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void WriteView(const std::string& text) const { std::ofstream(dir_ / "view.jsonl") << text; }
  std::string Problem() const {
    try {
      LoadReplayRun(dir_.string());
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return {};
  }

  std::filesystem::path dir_;
};

TEST_F(ReplayRunTest, ReadsTheHeaderAndEveryStepIntoOneArray) {
  WriteView("{\"robots\":[{\"id\":\"r1\"}],\"steps\":2}\n{\"step\":1}\n{\"step\":2}\n");
  const ReplayRun run = LoadReplayRun(dir_.string());
  EXPECT_EQ(nlohmann::json::parse(run.header_json)["steps"], 2);
  EXPECT_EQ(run.steps, 2);
  EXPECT_EQ(nlohmann::json::parse(run.steps_json), nlohmann::json::parse(R"([{"step":1},{"step":2}])"));
}

TEST_F(ReplayRunTest, MissingFileNamesItAndItsWriter) {
  EXPECT_THAT(Problem(), HasSubstr("view.jsonl (the evaluator writes it"));
}

TEST_F(ReplayRunTest, ALineThatIsNotJsonIsNamed) {
  WriteView("{\"robots\":[]}\n{\"step\":1}\n{\"step\":\n");
  EXPECT_THAT(Problem(), HasSubstr("line 3 is not JSON"));
}

TEST_F(ReplayRunTest, NoHeaderOrNoStepIsAnError) {
  WriteView("{\"step\":1}\n{\"step\":2}\n");
  EXPECT_THAT(Problem(), HasSubstr("has no header line"));
  WriteView("{\"robots\":[]}\n");
  EXPECT_THAT(Problem(), HasSubstr("holds no step"));
}

}  // namespace
}  // namespace mrslam::view
