#include "common/parallel_for.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace mrslam::common {
namespace {

TEST(ParallelForTest, EveryTaskRunsOnceAndDoneCountsThem) {
  for (const int threads : {1, 2, 5}) {
    std::vector<int> runs(37, 0);
    std::vector<int> done_order;
    ParallelFor(
        static_cast<int>(runs.size()), threads, [&](int i) { ++runs[static_cast<std::size_t>(i)]; },
        [&](int /*i*/, int finished) { done_order.push_back(finished); });
    EXPECT_EQ(runs, std::vector<int>(runs.size(), 1)) << threads << " threads";
    ASSERT_EQ(done_order.size(), runs.size());
    for (std::size_t k = 0; k < done_order.size(); ++k) EXPECT_EQ(done_order[k], static_cast<int>(k) + 1);
  }
}

TEST(ParallelForTest, AFailingTaskStopsNewOnesAndItsErrorIsRethrown) {
  int started = 0;
  const auto task = [&](int i) {
    ++started;
    if (i == 2) throw std::invalid_argument("task 2 failed");
  };
  try {
    ParallelFor(100, 1, task, [](int, int) {});
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "task 2 failed");
  }
  EXPECT_EQ(started, 3);  // one thread: tasks 0, 1, 2, then nothing more
}

TEST(ParallelForTest, NoTasks) {
  int calls = 0;
  ParallelFor(
      0, 4, [&](int) { ++calls; }, [&](int, int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace mrslam::common
