#pragma once

#include <atomic>
#include <string>
#include <vector>

// The DDS-Security files of a run (mrslam_launch --secure): made by make_identities.sh, which
// the build copies beside the executables.
namespace mrslam::launch {

// Makes (or completes) the identities of the named processes in dir: the two CAs, one
// certificate and key per name, the governance and one permissions document per name. Throws
// std::runtime_error with the script's one-line error if it fails or takes too long; returns
// false if stopped.
bool MakeIdentities(const std::string& dir, const std::vector<std::string>& names, const std::atomic<bool>& stop);

}  // namespace mrslam::launch
