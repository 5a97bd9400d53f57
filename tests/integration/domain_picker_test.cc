// The automatic DDS domain: a domain held by one pick is not picked again, in this process or
// in another, until it is released; nothing is left behind.
#include "scripts/launch/domain_picker.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>

namespace mrslam::launch {
namespace {

TEST(DomainPickerTest, AHeldDomainIsNotPickedAgainUntilReleased) {
  const pid_t pid = getpid();
  int first_domain = -1;
  {
    const DomainReservation first = PickFreeDomain(pid);
    ASSERT_GE(first.domain(), kFirstAutoDomain);
    ASSERT_LE(first.domain(), kLastAutoDomain);
    first_domain = first.domain();
    EXPECT_EQ(DomainReservation::TryHold(first_domain).domain(), -1);
    // The same starting point (same pid) skips the held domain.
    const DomainReservation second = PickFreeDomain(pid);
    ASSERT_GE(second.domain(), 0);
    EXPECT_NE(second.domain(), first_domain);
  }
  // Released with the object.
  const DomainReservation again = DomainReservation::TryHold(first_domain);
  EXPECT_EQ(again.domain(), first_domain);
}

TEST(DomainPickerTest, AnotherProcessDoesNotPickAHeldDomain) {
  const pid_t pid = getpid();
  const DomainReservation held = PickFreeDomain(pid);
  ASSERT_GE(held.domain(), 0);
  std::array<int, 2> pipe_fds{};
  ASSERT_EQ(pipe(pipe_fds.data()), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Another process (the child) picks from the same starting point.
    const DomainReservation mine = PickFreeDomain(pid);
    const int domain = mine.domain();
    const ssize_t written = write(pipe_fds[1], &domain, sizeof(domain));
    _exit(written == static_cast<ssize_t>(sizeof(domain)) ? 0 : 1);
  }
  close(pipe_fds[1]);
  int child_domain = -2;
  ASSERT_EQ(read(pipe_fds[0], &child_domain, sizeof(child_domain)), static_cast<ssize_t>(sizeof(child_domain)));
  close(pipe_fds[0]);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_GE(child_domain, 0);
  EXPECT_NE(child_domain, held.domain());
}

}  // namespace
}  // namespace mrslam::launch
