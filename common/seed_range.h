#pragma once

#include <string>
#include <vector>

namespace mrslam::common {

// The seeds of a many-seed run, A..B inclusive.
struct SeedRange {
  long long first = 0;
  long long last = 0;

  int size() const { return static_cast<int>(last - first + 1); }
  std::vector<long long> Seeds() const;
};

// "A..B" (or a single seed "A"), 0 <= A <= B, at most 10000 seeds; anything else throws
// std::runtime_error naming the flag.
SeedRange ParseSeedRange(const std::string& flag, const std::string& text);

}  // namespace mrslam::common
