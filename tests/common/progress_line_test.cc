#include "common/progress_line.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>

namespace mrslam::common {
namespace {

// ctest runs the test with stderr on a pipe or file: the line is not a terminal's.
TEST(ProgressLine, OffATerminalWritesNewLinesAtMostEveryTwoSecondsAndForcedOnes) {
  if (isatty(STDERR_FILENO) == 1) GTEST_SKIP() << "stderr is a terminal";
  testing::internal::CaptureStderr();
  {
    ProgressLine line;
    EXPECT_FALSE(line.tty());
    EXPECT_TRUE(line.Show("step 1/3"));
    EXPECT_FALSE(line.Show("step 2/3"));  // within 2 s of the first
    EXPECT_TRUE(line.Show("step 3/3", true));
  }
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "step 1/3\nstep 3/3\n");
}

}  // namespace
}  // namespace mrslam::common
