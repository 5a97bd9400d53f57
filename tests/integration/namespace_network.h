#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

// Hosts on one machine for partition tests: Linux network namespaces joined point to point by
// veth pairs (as root, with iproute2). Each namespace gets its loopback up; each link is a veth
// pair named "to-<peer>" at both ends with a /24 of its own (10.99.<link>.1 and .2), multicast
// on (Fast DDS sends its discovery on every interface, so no route is needed). No namespace
// forwards: one reaches only those it has a link to, so taking a link down cuts exactly that pair. Owns the namespaces
// (names "mrslam-<pid>-<name>") and deletes them, with their links, on destruction.
namespace mrslam::testing {

class NamespaceNetwork {
 public:
  // Why namespaces cannot be made here (not root, no `ip`, `ip netns add` refused), or empty.
  static std::string Unavailable();

  explicit NamespaceNetwork(const std::vector<std::string>& names);
  ~NamespaceNetwork();
  NamespaceNetwork(const NamespaceNetwork&) = delete;
  NamespaceNetwork& operator=(const NamespaceNetwork&) = delete;

  // Joins namespaces a and b by a veth pair. False (and a test failure) if `ip` refused.
  bool Link(const std::string& a, const std::string& b);
  // Takes the link between a and b down (Cut) or up again (Heal).
  bool Cut(const std::string& a, const std::string& b);
  bool Heal(const std::string& a, const std::string& b);
  // The command line that runs argv inside namespace `name`.
  std::vector<std::string> In(const std::string& name, const std::vector<std::string>& argv) const;

 private:
  std::string Full(const std::string& name) const;
  bool SetLink(const std::string& a, const std::string& b, const char* state);

  std::vector<std::string> names_;
  std::vector<std::string> created_;
  std::vector<std::pair<std::string, std::string>> links_;
};

}  // namespace mrslam::testing
