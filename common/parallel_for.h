#pragma once

#include <functional>

namespace mrslam::common {

// Runs task(i) for every i in [0, count) on up to `threads` threads, each taking the next index
// from a shared counter. After a task ends, done(i, finished) runs under one lock (finished: how
// many tasks have ended so far), for progress and bookkeeping. If a task throws, no new task
// starts, and once the running ones have ended the first error is rethrown as
// std::runtime_error; a task that must not stop the others catches its own errors.
void ParallelFor(int count, int threads, const std::function<void(int)>& task,
                 const std::function<void(int, int)>& done);

}  // namespace mrslam::common
