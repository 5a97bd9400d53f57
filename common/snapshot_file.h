#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

// A process's state on disk, for a process of the same run that starts again after it died: one
// file per process, replaced atomically (written beside it, renamed over it), so a kill of the
// process at any moment leaves either the previous snapshot or the new one whole.
// Layout: the magic line "mrslam-snapshot 1\n", the build's fingerprint, the run's (which run
// and process it belongs to), the step, the payload (an Archive's bytes), then the FNV-1a 64
// checksum of everything before it.
namespace mrslam::common {

class SnapshotError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Snapshot {
  std::uint32_t step = 0;  // the last step the state includes
  std::string payload;
};

// Writes the snapshot of `step` to path atomically; throws SnapshotError (naming the path) when
// the file system refuses.
void WriteSnapshot(const std::string& path, const std::string& run_fingerprint, const Snapshot& snapshot);

// The snapshot at path; none when there is no file. SnapshotError, in one line naming the path,
// when it is truncated, corrupt, of another build or of another run (run_fingerprint differs).
std::optional<Snapshot> ReadSnapshot(const std::string& path, const std::string& run_fingerprint);

}  // namespace mrslam::common
