#pragma once

#include <string>

// What Fast DDS's shared-memory transport leaves in /dev/shm when a process of a run is killed
// (SIGKILL gives it no chance to remove its files): its segment and the port files of the run's
// domain that it held open. A clean exit leaves nothing.
namespace mrslam::launch {

// Removes, from dir (normally /dev/shm), the files no living process holds: every segment
// "fastrtps_<16 characters>" whose lock file "<segment>_el" nobody has locked, and every port of
// the domain's range (RTPS port mapping: 7400 + 250 * domain + 0..249) whose "_el" lock file is
// missing or unlocked, with its "_el", "_sl" and "sem.<port>_mutex" files. Files in use (their
// lock held by a living process, on any domain) are left alone. Returns how many files it removed.
int RemoveShmLeftovers(int domain, const std::string& dir = "/dev/shm");

}  // namespace mrslam::launch
