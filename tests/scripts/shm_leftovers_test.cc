// RemoveShmLeftovers in a folder of its own: it removes the segments and the domain's ports that
// no process holds, and leaves the held ones, other domains' ports and other files.
#include "scripts/launch/shm_leftovers.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <gtest/gtest.h>

namespace mrslam::launch {
namespace {

namespace fs = std::filesystem;

class ShmLeftoversTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("mrslam-shm-leftovers-" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (held_fd_ >= 0) close(held_fd_);
    fs::remove_all(dir_);
  }
  void Touch(const std::string& name) const { std::ofstream(dir_ / name) << "x"; }
  // Holds the lock file as Fast DDS does while its segment or port is open.
  void Hold(const std::string& lock) {
    held_fd_ = open((dir_ / lock).c_str(), O_RDONLY | O_CLOEXEC);
    ASSERT_GE(held_fd_, 0);
    ASSERT_EQ(flock(held_fd_, LOCK_EX | LOCK_NB), 0);
  }
  std::set<std::string> Left() const {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.insert(e.path().filename().string());
    return names;
  }

  fs::path dir_;
  int held_fd_ = -1;
};

TEST_F(ShmLeftoversTest, RemovesWhatNoProcessHoldsAndNothingElse) {
  constexpr int kDomain = 109;  // ports 34650..34899
  for (const std::string segment : {"fastrtps_0123456789abcdef", "fastrtps_fedcba9876543210"}) {
    Touch(segment);
    Touch(segment + "_el");
  }
  Hold("fastrtps_fedcba9876543210_el");
  for (const std::string port : {"fastrtps_port34660", "fastrtps_port34662"}) {
    Touch(port);
    Touch("sem." + port + "_mutex");
  }
  Touch("fastrtps_port34662_el");
  Touch("sem.fastrtps_port34664_mutex");  // a port whose files are gone but its mutex
  Touch("fastrtps_port7410");             // domain 0
  Touch("unrelated");

  EXPECT_EQ(RemoveShmLeftovers(kDomain, dir_.string()), 2 + 2 + 3 + 1);
  const std::set<std::string> expected = {"fastrtps_fedcba9876543210", "fastrtps_fedcba9876543210_el",
                                          "fastrtps_port7410", "unrelated"};
  EXPECT_EQ(Left(), expected);
}

TEST_F(ShmLeftoversTest, LeavesAHeldPortAlone) {
  Touch("fastrtps_port7410");
  Touch("fastrtps_port7410_el");
  Touch("sem.fastrtps_port7410_mutex");
  Hold("fastrtps_port7410_el");
  EXPECT_EQ(RemoveShmLeftovers(0, dir_.string()), 0);
  EXPECT_EQ(Left().size(), 3U);
}

}  // namespace
}  // namespace mrslam::launch
