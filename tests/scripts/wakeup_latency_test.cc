// WakeupLatencyRequest against a file of its own in place of /dev/cpu_dma_latency: it writes the
// bound as the kernel reads it; a file it cannot open or write to gives one line naming it.
#include "scripts/launch/wakeup_latency.h"

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace mrslam::launch {
namespace {

namespace fs = std::filesystem;

TEST(WakeupLatencyRequest, WritesTheBoundAsA32BitInteger) {
  const fs::path device = fs::temp_directory_path() / ("mrslam-wakeup-" + std::to_string(getpid()));
  std::ofstream(device).close();
  {
    const WakeupLatencyRequest request(7, device.string());
    EXPECT_TRUE(request.held());
    EXPECT_TRUE(request.error().empty());
    std::ifstream in(device, std::ios::binary);
    std::int32_t value = -1;
    in.read(reinterpret_cast<char*>(&value), sizeof(value));
    EXPECT_EQ(in.gcount(), static_cast<std::streamsize>(sizeof(value)));
    EXPECT_EQ(value, 7);
    EXPECT_EQ(fs::file_size(device), sizeof(value));
  }
  fs::remove(device);
}

TEST(WakeupLatencyRequest, AFileItCannotOpenIsNamedInOneLine) {
  const std::string device = "/nonexistent-mrslam-dir/cpu_dma_latency";
  const WakeupLatencyRequest request(0, device);
  EXPECT_FALSE(request.held());
  EXPECT_NE(request.error().find(device), std::string::npos);
  EXPECT_EQ(request.error().find('\n'), std::string::npos);
}

TEST(WakeupLatencyRequest, AFileThatRefusesTheWriteIsNotHeld) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  const WakeupLatencyRequest request(0, "/dev/full");  // opens, and every write fails (no space)
  EXPECT_FALSE(request.held());
  EXPECT_NE(request.error().find("cannot write to /dev/full"), std::string::npos) << request.error();
}

}  // namespace
}  // namespace mrslam::launch
