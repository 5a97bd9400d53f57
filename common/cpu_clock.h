#pragma once

#include <sys/resource.h>
#include <time.h>

namespace mrslam::common {

// CPU time the calling thread has used, in seconds (CLOCK_THREAD_CPUTIME_ID): a cost measure that
// other processes on a shared machine do not inflate, unlike wall time.
inline double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// CPU time (user and system) of this process and of its children that have ended and been
// waited for, in seconds: what a launcher and the run it started have used.
inline double ProcessTreeCpuSeconds() {
  const auto seconds = [](const rusage& u) {
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  };
  rusage self{};
  rusage children{};
  getrusage(RUSAGE_SELF, &self);
  getrusage(RUSAGE_CHILDREN, &children);
  return seconds(self) + seconds(children);
}

}  // namespace mrslam::common
