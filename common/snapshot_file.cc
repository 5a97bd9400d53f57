#include "common/snapshot_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "common/archive.h"

namespace mrslam::common {

namespace {

constexpr char kMagic[] = "mrslam-snapshot 1\n";

// What must match for raw bytes to read back: the compiler and the sizes of the basic types.
std::string BuildFingerprint() {
  std::ostringstream out;
#ifdef __VERSION__
  out << __VERSION__;
#endif
  out << " ptr" << sizeof(void*) << " long" << sizeof(long) << " double" << sizeof(double);
  return out.str();
}

std::uint64_t Fnv1a(const std::string& bytes) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

[[noreturn]] void Fail(const std::string& path, const std::string& why) {
  throw SnapshotError("snapshot " + path + ": " + why);
}

// Writes all bytes to a new file (not flushed to the disk: the rename makes it atomic against
// the process's death, which is what a restart needs, not against the machine's).
void WriteFile(const std::string& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) Fail(path, std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      Fail(path, why);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) Fail(path, std::strerror(errno));
}

}  // namespace

void WriteSnapshot(const std::string& path, const std::string& run_fingerprint, const Snapshot& snapshot) {
  Archive ar = Archive::ForWriting();
  std::string magic = kMagic;
  std::string build = BuildFingerprint();
  std::string run = run_fingerprint;
  std::uint32_t step = snapshot.step;
  std::string payload = snapshot.payload;
  ar(magic, build, run, step, payload);
  std::string bytes = ar.bytes();
  std::uint64_t checksum = Fnv1a(bytes);
  bytes.append(reinterpret_cast<const char*>(&checksum), sizeof checksum);
  const std::string temporary = path + ".new";
  WriteFile(temporary, bytes);
  if (std::rename(temporary.c_str(), path.c_str()) != 0) Fail(path, std::strerror(errno));
}

std::optional<Snapshot> ReadSnapshot(const std::string& path, const std::string& run_fingerprint) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::uint64_t checksum = 0;
  if (bytes.size() < sizeof checksum) Fail(path, "truncated");
  std::memcpy(&checksum, bytes.data() + bytes.size() - sizeof checksum, sizeof checksum);
  bytes.resize(bytes.size() - sizeof checksum);
  if (Fnv1a(bytes) != checksum) Fail(path, "corrupt (its checksum does not match)");
  Archive ar = Archive::ForReading(std::move(bytes));
  std::string magic, build, run;
  Snapshot snapshot;
  try {
    ar(magic, build, run, snapshot.step, snapshot.payload);
  } catch (const ArchiveError& e) {
    Fail(path, e.what());
  }
  if (magic != kMagic || !ar.AtEnd()) Fail(path, "not a snapshot of this format");
  if (build != BuildFingerprint()) Fail(path, "written by another build (" + build + ")");
  if (run != run_fingerprint) Fail(path, "of another run (" + run + ", this is " + run_fingerprint + ")");
  return snapshot;
}

}  // namespace mrslam::common
