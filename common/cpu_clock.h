#pragma once

#include <time.h>

namespace mrslam::common {

// CPU time the calling thread has used, in seconds (CLOCK_THREAD_CPUTIME_ID): a cost measure that
// other processes on a shared machine do not inflate, unlike wall time.
inline double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace mrslam::common
