#pragma once

#include <sys/types.h>

// Choosing a DDS domain that no other run on this host uses.
namespace mrslam::launch {

// First and last domain ids the launcher picks from (busy ones are skipped). Tests that pass
// their own --domain use ids below kFirstAutoDomain, so an automatic pick never races them.
constexpr int kFirstAutoDomain = 150;
constexpr int kLastAutoDomain = 232;

// The UDP unicast port of participant 0's metatraffic in domain d (RTPS port mapping:
// PB 7400 + DG 250 * d + d1 10 + PG 2 * participant id).
int MetatrafficUnicastPort(int domain);

// True when no process holds participant 0's metatraffic port of the domain (a bind test).
bool DomainLooksFree(int domain);

// Tries the domains kFirstAutoDomain..kLastAutoDomain, starting at one derived from pid and
// wrapping around, and returns the first that looks free; -1 if none.
int PickFreeDomain(pid_t pid);

}  // namespace mrslam::launch
