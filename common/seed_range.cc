#include "common/seed_range.h"

#include <regex>
#include <stdexcept>

namespace mrslam::common {

namespace {
constexpr long long kMaxSeeds = 10000;
}  // namespace

std::vector<long long> SeedRange::Seeds() const {
  std::vector<long long> seeds;
  for (long long s = first; s <= last; ++s) seeds.push_back(s);
  return seeds;
}

SeedRange ParseSeedRange(const std::string& flag, const std::string& text) {
  static const std::regex pattern(R"(^\s*(\d{1,15})\s*(?:\.\.\s*(\d{1,15})\s*)?$)");
  std::smatch m;
  if (!std::regex_match(text, m, pattern)) {
    throw std::runtime_error(flag + " '" + text + "' is not of the form A..B with 0 <= A <= B");
  }
  SeedRange range;
  range.first = std::stoll(m[1].str());
  range.last = m[2].matched ? std::stoll(m[2].str()) : range.first;
  if (range.last < range.first) throw std::runtime_error(flag + " '" + text + "': the last seed is below the first");
  if (range.last - range.first >= kMaxSeeds) {
    throw std::runtime_error(flag + " '" + text + "': more than " + std::to_string(kMaxSeeds) + " seeds");
  }
  return range;
}

}  // namespace mrslam::common
