#pragma once

#include <sys/types.h>

#include <string>

// Choosing a DDS domain that no other run on this host uses.
namespace mrslam::launch {

// First and last domain ids the launcher picks from (busy ones are skipped). Tests that pass
// their own --domain use ids below kFirstAutoDomain, so an automatic pick never races them.
constexpr int kFirstAutoDomain = 150;
constexpr int kLastAutoDomain = 232;

// The UDP unicast port of participant 0's metatraffic in domain d (RTPS port mapping:
// PB 7400 + DG 250 * d + d1 10 + PG 2 * participant id).
int MetatrafficUnicastPort(int domain);

// Where a run on domain d serves discovery (mrslam_launch --discovery-server): 127.0.0.1 and a
// port below the RTPS ports of every domain (7100 + d), so the domain's hold covers it too.
std::string DiscoveryServerAddress(int domain);

// True when no process holds participant 0's metatraffic port of the domain (a bind test).
bool DomainLooksFree(int domain);

// A domain held for one run. While it lives no other pick on this host, in this process or
// another, returns the same domain: the hold is an abstract Unix socket named
// "mrslam-dds-domain-<d>", which the kernel releases with the object or with the process,
// however it ends (nothing is left in the file system). The port test alone would let two
// pickers take one domain in the time between a pick and its first participant.
class DomainReservation {
 public:
  DomainReservation() = default;
  ~DomainReservation();
  DomainReservation(DomainReservation&& other) noexcept;
  DomainReservation& operator=(DomainReservation&& other) noexcept;
  DomainReservation(const DomainReservation&) = delete;
  DomainReservation& operator=(const DomainReservation&) = delete;

  // The domain; -1 when none was free.
  int domain() const { return domain_; }

  // Holds the domain if no one holds it yet.
  static DomainReservation TryHold(int domain);

 private:
  DomainReservation(int domain, int fd) : domain_(domain), fd_(fd) {}
  void Release();

  int domain_ = -1;
  int fd_ = -1;
};

// Tries the domains kFirstAutoDomain..kLastAutoDomain, starting at one derived from pid and
// wrapping around, and holds the first that no other pick holds and that looks free; domain()
// is -1 if none.
DomainReservation PickFreeDomain(pid_t pid);

}  // namespace mrslam::launch
