#include "common/parallel_for.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace mrslam::common {

void ParallelFor(int count, int threads, const std::function<void(int)>& task,
                 const std::function<void(int, int)>& done) {
  std::atomic<int> next{0};
  std::mutex mutex;
  int finished = 0;
  std::string error;
  bool failed = false;
  const auto worker = [&]() {
    for (int i = next++; i < count; i = next++) {
      try {
        task(i);
      } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!failed) error = e.what();
        failed = true;
        next = count;
        return;
      }
      const std::lock_guard<std::mutex> lock(mutex);
      done(i, ++finished);
    }
  };
  const int workers = std::max(1, std::min(threads, count));
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(workers));
  for (int t = 0; t < workers; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failed) throw std::runtime_error(error);
}

}  // namespace mrslam::common
