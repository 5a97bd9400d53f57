#include "tests/integration/namespace_network.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include <gtest/gtest.h>

#include "tests/integration/child_process.h"

namespace mrslam::testing {
namespace {

constexpr char kIp[] = "/usr/sbin/ip";

// Runs `ip args...`; true on exit code 0. Its output goes to /dev/null.
bool Ip(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {kIp};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess ip(argv, "/dev/null");
  return ip.started() && ip.WaitExit(std::chrono::seconds(20)) == std::optional<int>(0);
}

// Waits until device `dev` of namespace `ns` has a carrier (its peer end is up too): a process
// that starts before leaves the link out of its DDS transports. False after 10 s.
bool WaitForCarrier(const std::string& ns, const std::string& dev) {
  const std::string out = "/tmp/mrslam-link-" + std::to_string(getpid()) + "-" + dev;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  bool up = false;
  while (!up && std::chrono::steady_clock::now() < deadline) {
    ChildProcess show({kIp, "-n", ns, "-o", "link", "show", "dev", dev}, out);
    up = show.WaitExit(std::chrono::seconds(20)) == std::optional<int>(0) &&
         ReadFile(out).find("state UP") != std::string::npos;
    if (!up) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::remove(out.c_str());
  return up;
}

}  // namespace

std::string NamespaceNetwork::Unavailable() {
  if (geteuid() != 0) return "network namespaces need root (ip netns add)";
  if (access(kIp, X_OK) != 0) return std::string(kIp) + " not found (apt-get install iproute2)";
  const std::string probe = "mrslam-probe-" + std::to_string(getpid());
  if (!Ip({"netns", "add", probe})) return "`ip netns add` is refused here (no network namespaces)";
  Ip({"netns", "delete", probe});
  return {};
}

NamespaceNetwork::NamespaceNetwork(const std::vector<std::string>& names) : names_(names) {
  for (const auto& n : names_) {
    if (!Ip({"netns", "add", Full(n)})) {
      ADD_FAILURE() << "cannot add network namespace " << Full(n);
      continue;
    }
    created_.push_back(Full(n));
    if (!Ip({"-n", Full(n), "link", "set", "lo", "up"})) ADD_FAILURE() << "cannot bring lo up in " << Full(n);
  }
}

NamespaceNetwork::~NamespaceNetwork() {
  for (const auto& n : created_) Ip({"netns", "delete", n});
}

std::string NamespaceNetwork::Full(const std::string& name) const {
  return "mrslam-" + std::to_string(getpid()) + "-" + name;
}

bool NamespaceNetwork::Link(const std::string& a, const std::string& b) {
  const std::string subnet = "10.99." + std::to_string(links_.size()) + ".";
  const std::string to_a = "to-" + a;
  const std::string to_b = "to-" + b;
  bool ok = Ip({"link", "add", to_b, "netns", Full(a), "type", "veth", "peer", "name", to_a, "netns", Full(b)});
  ok = ok && Ip({"-n", Full(a), "addr", "add", subnet + "1/24", "dev", to_b});
  ok = ok && Ip({"-n", Full(b), "addr", "add", subnet + "2/24", "dev", to_a});
  ok = ok && Ip({"-n", Full(a), "link", "set", to_b, "up", "multicast", "on"});
  ok = ok && Ip({"-n", Full(b), "link", "set", to_a, "up", "multicast", "on"});
  ok = ok && WaitForCarrier(Full(a), to_b) && WaitForCarrier(Full(b), to_a);
  if (!ok) ADD_FAILURE() << "cannot link " << a << " and " << b;
  links_.emplace_back(a, b);
  return ok;
}

bool NamespaceNetwork::SetLink(const std::string& a, const std::string& b, const char* state) {
  const bool ok = Ip({"-n", Full(a), "link", "set", "to-" + b, state});
  if (!ok) ADD_FAILURE() << "cannot set the link " << a << "-" << b << " " << state;
  return ok;
}

bool NamespaceNetwork::Cut(const std::string& a, const std::string& b) { return SetLink(a, b, "down"); }
bool NamespaceNetwork::Heal(const std::string& a, const std::string& b) { return SetLink(a, b, "up"); }

std::vector<std::string> NamespaceNetwork::In(const std::string& name, const std::vector<std::string>& argv) const {
  std::vector<std::string> out = {kIp, "netns", "exec", Full(name)};
  out.insert(out.end(), argv.begin(), argv.end());
  return out;
}

}  // namespace mrslam::testing
