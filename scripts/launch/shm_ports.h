#pragma once

#include <string>

// The shared-memory files a run's processes leave behind when they are killed.
namespace mrslam::launch {

// The range of ports Fast DDS gives the participants of a DDS domain (the default port
// parameters: 7400 + 250 * domain, 250 ports per domain), which its shared-memory transport also
// uses to name its port files.
struct DomainPorts {
  int first = 0;  // inclusive
  int last = 0;   // inclusive
};
DomainPorts PortsOfDomain(int domain);

// The port a Fast DDS shared-memory port file is named after ("fastrtps_port<N>",
// "sem.fastrtps_port<N>_mutex"), or -1 for any other name.
int PortOfShmFile(const std::string& name);

// Removes from shm_dir (normally /dev/shm) the port files of domain's ports. A participant that
// ends cleanly removes its own; one killed with SIGKILL leaves them for good, and the files of the
// ports it wrote to stay too. Call it only when no process of the domain runs any more (the
// launcher holds its domain for the run). Returns the number of files removed.
int RemoveShmPortFiles(int domain, const std::string& shm_dir = "/dev/shm");

}  // namespace mrslam::launch
