// Every executable answers a bad command line (tests/integration/data/bad_command_lines.txt) at
// once with one line on stderr naming the problem and a non-zero exit, before it starts anything.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/integration/child_process.h"

namespace mrslam {
namespace {

using testing::BinPath;
using testing::ChildProcess;
using testing::SourcePath;

struct BadCommandLine {
  std::vector<std::string> argv;
  std::string expected;  // what the error line must contain
  std::string text;
};

std::vector<BadCommandLine> ReadFixtures(const std::string& out_dir) {
  std::vector<BadCommandLine> out;
  std::ifstream in(SourcePath("tests/integration/data/bad_command_lines.txt"));
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const auto arrow = line.find(" => ");
    if (arrow == std::string::npos) continue;
    BadCommandLine c{{}, line.substr(arrow + 4), line};
    std::istringstream words(line.substr(0, arrow));
    for (std::string w; words >> w;) {
      if (w == "SCENARIO") w = SourcePath("config/paper_two_robots.yaml");
      if (w == "FIELD") w = SourcePath("config/dynamic_world.yaml");
      if (w == "OUT") w = out_dir;
      c.argv.push_back(c.argv.empty() ? BinPath(w) : w);
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<std::string> NonEmptyLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    if (!l.empty()) lines.push_back(l);
  }
  return lines;
}

TEST(BadCommandLineTest, EachIsOneLineNamingTheProblemAndANonZeroExit) {
  const testing::TempDir temp_dir("mrslam-bad-cli");
  const std::string log = temp_dir.path() + "/stderr.log";
  const std::vector<BadCommandLine> fixtures = ReadFixtures(temp_dir.path() + "/out");
  EXPECT_GE(fixtures.size(), 25U);
  for (const BadCommandLine& c : fixtures) {
    ChildProcess child(c.argv, log);
    const std::optional<int> status = child.WaitExit(std::chrono::seconds(10));
    const std::string output = testing::ReadFile(log);
    ASSERT_TRUE(status.has_value()) << c.text << ": still running after 10 s";
    EXPECT_NE(*status, 0) << c.text;
    const std::vector<std::string> lines = NonEmptyLines(output);
    ASSERT_EQ(lines.size(), 1U) << c.text << ":\n" << output;
    EXPECT_NE(lines[0].find(c.expected), std::string::npos) << c.text << ": " << lines[0];
  }
}

}  // namespace
}  // namespace mrslam
