// The launcher's clean-up of the shared-memory port files that killed processes leave.
#include "scripts/launch/shm_ports.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace mrslam::launch {
namespace {

namespace fs = std::filesystem;

TEST(ShmPortsTest, EachDomainHasItsOwnRangeOfPorts) {
  EXPECT_EQ(PortsOfDomain(0).first, 7400);
  EXPECT_EQ(PortsOfDomain(0).last, 7649);
  EXPECT_EQ(PortsOfDomain(102).first, 32900);
  EXPECT_EQ(PortsOfDomain(102).last, PortsOfDomain(103).first - 1);
}

TEST(ShmPortsTest, OnlyPortFilesAndTheirSemaphoresHaveAPort) {
  EXPECT_EQ(PortOfShmFile("fastrtps_port32910"), 32910);
  EXPECT_EQ(PortOfShmFile("sem.fastrtps_port32910_mutex"), 32910);
  for (const char* other : {"fastrtps_port", "fastrtps_port12a", "sem.fastrtps_port32910", "sem.fastrtps_port_mutex",
                            "fastrtps_8f3c0a1b", "fastrtps_port32910_el", "chromium.abc", ""}) {
    EXPECT_EQ(PortOfShmFile(other), -1) << other;
  }
}

TEST(ShmPortsTest, RemovesThePortFilesOfTheDomainAndNothingElse) {
  const fs::path dir = fs::temp_directory_path() / ("shm_ports_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const auto touch = [&](const std::string& name) { std::ofstream(dir / name) << "x"; };
  for (const char* name : {"fastrtps_port32900", "sem.fastrtps_port32900_mutex", "fastrtps_port33149",
                           "fastrtps_port32899", "fastrtps_port33150", "fastrtps_8f3c0a1b", "other"}) {
    touch(name);
  }
  EXPECT_EQ(RemoveShmPortFiles(102, dir.string()), 3);
  for (const char* kept : {"fastrtps_port32899", "fastrtps_port33150", "fastrtps_8f3c0a1b", "other"}) {
    EXPECT_TRUE(fs::exists(dir / kept)) << kept;
  }
  EXPECT_FALSE(fs::exists(dir / "fastrtps_port32900"));
  EXPECT_EQ(RemoveShmPortFiles(102, (dir / "missing").string()), 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace mrslam::launch
