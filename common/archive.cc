#include "common/archive.h"

#include <cstring>
#include <limits>

namespace mrslam::common {

void Archive::Raw(void* data, std::size_t n) {
  if (n == 0) return;
  if (!loading_) {
    bytes_.append(static_cast<const char*>(data), n);
    return;
  }
  Expect(n, 1);
  std::memcpy(data, bytes_.data() + position_, n);
  position_ += n;
}

std::size_t Archive::Count(std::size_t n, std::size_t min_bytes) {
  auto count = static_cast<std::uint64_t>(n);
  Raw(&count, sizeof count);
  if (loading_) {
    if (count > std::numeric_limits<std::size_t>::max()) throw ArchiveError("archive: a count beyond this machine");
    Expect(static_cast<std::size_t>(count), min_bytes);
  }
  return static_cast<std::size_t>(count);
}

void Archive::Expect(std::size_t count, std::size_t bytes) const {
  const std::size_t left = bytes_.size() - position_;
  if (bytes != 0 && count > left / bytes) {
    throw ArchiveError("archive: " + std::to_string(count) + " element(s) of " + std::to_string(bytes) +
                       " byte(s) announced where " + std::to_string(left) + " byte(s) remain (truncated or corrupt)");
  }
}

}  // namespace mrslam::common
