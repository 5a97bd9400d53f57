// Multi-process: DDS-Security (docs/security.md). A secure run gives the same numbers as a plain
// one; an outsider without a certificate on the same domain reads nothing and injects nothing; an
// authenticated robot cannot write as another robot, on the truth or on another's peer topics;
// bad security files end a process with one line naming the file and the problem.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <set>

#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <nlohmann/json.hpp>

#include "common/dds/msg_conversion.h"
#include "common/dds/participant.h"
#include "mrslamPubSubTypes.h"
#include "tests/integration/child_process.h"
#include "tests/integration/launch_helpers.h"

namespace mrslam {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;
using testing::BinPath;
using testing::ChildProcess;
using ::testing::HasSubstr;
using testing::ReadFile;
using testing::SourcePath;

// This test's own DDS domains: 135..139 and 145 (ctest runs the tests of this file in parallel).
constexpr int kPlainDomain = 135;
constexpr int kSecureDomain = 136;
constexpr int kOutsiderDomain = 137;
constexpr int kImpersonationDomain = 138;
constexpr int kBadFilesDomain = 139;
constexpr int kOutsiderPlainDomain = 145;

const std::vector<std::string> kProcesses = {"world_sim", "evaluator", "monitor", "r1", "r2"};

bool HasOpenssl() { return std::system("command -v openssl >/dev/null 2>&1") == 0; }

#define SKIP_WITHOUT_OPENSSL() \
  if (!HasOpenssl()) GTEST_SKIP() << "openssl not found: the DDS-Security tests need it (apt-get install openssl)"

// Makes the identities of `names` into dir with scripts/security/make_identities.sh.
::testing::AssertionResult MakeIdentities(const std::string& dir, const std::vector<std::string>& names) {
  std::vector<std::string> argv = {"/bin/bash", SourcePath("scripts/security/make_identities.sh"), dir};
  argv.insert(argv.end(), names.begin(), names.end());
  ChildProcess script(argv, dir + ".make_identities.log");
  if (script.WaitExit(seconds(120)) != std::optional<int>(0)) {
    return ::testing::AssertionFailure() << ReadFile(dir + ".make_identities.log");
  }
  return ::testing::AssertionSuccess();
}

std::vector<std::string> LaunchArgs(const std::string& out, int domain, int steps, bool secure) {
  std::vector<std::string> extra = {"--no-plots", "--set", "run.steps=" + std::to_string(steps)};
  if (secure) extra.emplace_back("--secure");
  return testing::TwoRobotLaunchArgs(out, domain, extra);
}

nlohmann::json Summary(const std::string& out) {
  try {
    return nlohmann::json::parse(ReadFile(out + "/summary.json"));
  } catch (const std::exception&) {
    return {};
  }
}

// Runs mrslam_launch to its end and returns its summary (null if it failed).
nlohmann::json RunLauncher(const std::string& out, int domain, int steps, bool secure) {
  ChildProcess launcher(LaunchArgs(out, domain, steps, secure), out + ".log");
  const auto code = launcher.WaitExit(seconds(300));
  EXPECT_EQ(code, std::optional<int>(0)) << ReadFile(out + ".log");
  return Summary(out);
}

void ExpectSameNumbers(const nlohmann::json& secure, const nlohmann::json& plain) {
  for (const std::string id : {"r1", "r2"}) {
    ASSERT_TRUE(secure["robots"].contains(id)) << secure.dump(2);
    ASSERT_TRUE(plain["robots"].contains(id)) << plain.dump(2);
    const auto& s = secure["robots"][id];
    const auto& p = plain["robots"][id];
    EXPECT_EQ(s["position_rmse_m"].get<double>(), p["position_rmse_m"].get<double>()) << id;
    EXPECT_EQ(s["heading_rmse_deg"].get<double>(), p["heading_rmse_deg"].get<double>()) << id;
    EXPECT_EQ(s["rejected_samples"].get<unsigned>(), 0U) << id;
  }
}

TEST(SecurityTest, SecureRunGivesTheSameNumbersAsAPlainRun) {
  SKIP_WITHOUT_OPENSSL();
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-secure-run");
  const std::string plain_out = temp_dir.path() + "/plain";
  const std::string secure_out = temp_dir.path() + "/secure";
  const nlohmann::json plain = RunLauncher(plain_out, kPlainDomain, 30, false);
  const nlohmann::json secure = RunLauncher(secure_out, kSecureDomain, 30, true);
  ASSERT_FALSE(plain.is_null());
  ASSERT_FALSE(secure.is_null());
  ExpectSameNumbers(secure, plain);
  // The launcher made one identity per process, the keys readable by their owner only.
  const fs::path security = fs::path(secure_out) / "security";
  for (const auto& name : kProcesses) {
    struct stat key {};
    ASSERT_EQ(stat((security / (name + "_key.pem")).c_str(), &key), 0) << name;
    EXPECT_EQ(key.st_mode & 0777, 0600U) << name;
    EXPECT_TRUE(fs::exists(security / ("permissions_" + name + ".p7s"))) << name;
  }
  EXPECT_FALSE(fs::exists(plain_out + "/security"));
}

// Records the participants that announce themselves on the domain (called on a DDS thread).
class AnnouncedNames : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant* /*participant*/,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    std::lock_guard<std::mutex> lock(mutex_);
    names_.insert(info.info.m_participantName.to_string());
  }
  bool Has(const std::string& name) {
    std::lock_guard<std::mutex> lock(mutex_);
    return names_.count(name) > 0;
  }

 private:
  std::mutex mutex_;
  std::set<std::string> names_;
};

// An outsider without a certificate on the run's domain: it sees the secure participants announce
// themselves, but its truth reader and its r1 lidar writer (scans of every step, waiting for a
// late reader) never match, it reads nothing, and the run ends with the plain run's numbers.
TEST(SecurityTest, OutsiderWithoutCertificateReadsAndInjectsNothing) {
  SKIP_WITHOUT_OPENSSL();
  unsetenv("MRSLAM_DOMAIN");
  constexpr int kSteps = 12;
  const testing::TempDir temp_dir("mrslam-outsider");
  const std::string out = temp_dir.path() + "/secure";
  const nlohmann::json plain = RunLauncher(temp_dir.path() + "/plain", kOutsiderPlainDomain, kSteps, false);

  AnnouncedNames announced;
  dds::Participant outsider({kOutsiderDomain, "outsider", false});
  outsider.get()->set_listener(&announced, eprosima::fastdds::dds::StatusMask::none());
  dds::Reader<msg::GroundTruthPubSubType> truth(outsider, dds::kTruthTopic);
  dds::Writer<msg::SensorStepPubSubType> sensors(outsider, dds::SensorTopic("r1"));
  for (std::uint32_t k = 1; k <= kSteps; ++k) {
    const common::Stamp stamp{"r1", k, 0.65 * k};
    common::SensorStep forged{{stamp, {{0.65 * k, 3.0, 0.5, -1}}, {}}, {stamp, {}}, {stamp, {}}};
    ASSERT_TRUE(sensors.Write(dds::ToMsg(forged)));
  }
  ChildProcess launcher(LaunchArgs(out, kOutsiderDomain, kSteps, true), out + ".log");
  int most_matched = 0;
  std::optional<int> code;
  const auto deadline = std::chrono::steady_clock::now() + seconds(300);
  while (!code && std::chrono::steady_clock::now() < deadline) {
    code = launcher.WaitExit(milliseconds(20));
    most_matched = std::max({most_matched, truth.MatchedWriters(), sensors.MatchedReaders()});
  }
  const bool saw_world_sim = announced.Has("world_sim");
  outsider.get()->set_listener(nullptr);
  ASSERT_EQ(code, std::optional<int>(0)) << ReadFile(out + ".log");
  EXPECT_TRUE(saw_world_sim) << "the outsider should see the simulator announce itself on the domain";
  EXPECT_EQ(most_matched, 0);
  msg::GroundTruth sample;
  EXPECT_FALSE(truth.TryTake(&sample));
  const nlohmann::json secure = Summary(out);
  ASSERT_FALSE(secure.is_null());
  ASSERT_FALSE(plain.is_null());
  ExpectSameNumbers(secure, plain);
}

// r2, authenticated with its own certificate, may write its own estimate and its own peer topics,
// but not r1's sensors, r1's estimate, the truth, or a peer topic in r1's name; nor read the truth
// or r1's peer topics.
TEST(SecurityTest, AnAuthenticatedRobotCannotSpeakForAnother) {
  SKIP_WITHOUT_OPENSSL();
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-impersonation");
  const std::string dir = temp_dir.path() + "/security";
  ASSERT_TRUE(MakeIdentities(dir, kProcesses));
  dds::Participant r2({kImpersonationDomain, "robot_agent/r2", false, dir, "r2"});
  EXPECT_NO_THROW(dds::Writer<msg::EstimatePubSubType>(r2, dds::EstimateTopic("r2")));
  EXPECT_NO_THROW(dds::Writer<msg::RelativeMeasurementPubSubType>(r2, dds::PeerTopic("r1", "r2", "relative")));
  EXPECT_NO_THROW(dds::Reader<msg::MapSnapshotPubSubType>(r2, dds::PeerTopic("r2", "r1", "map")));
  EXPECT_THROW(dds::Writer<msg::SensorStepPubSubType>(r2, dds::SensorTopic("r1")), dds::DdsError);
  EXPECT_THROW(dds::Writer<msg::EstimatePubSubType>(r2, dds::EstimateTopic("r1")), dds::DdsError);
  EXPECT_THROW(dds::Writer<msg::GroundTruthPubSubType>(r2, dds::kTruthTopic), dds::DdsError);
  EXPECT_THROW(dds::Writer<msg::RelativeMeasurementPubSubType>(r2, dds::PeerTopic("r2", "r1", "relative")),
               dds::DdsError);
  EXPECT_THROW(dds::Writer<msg::MapSnapshotPubSubType>(r2, dds::PeerTopic("r1", "r1", "map")), dds::DdsError);
  EXPECT_THROW(dds::Reader<msg::GroundTruthPubSubType>(r2, dds::kTruthTopic), dds::DdsError);
  EXPECT_THROW(dds::Reader<msg::RelativeMeasurementPubSubType>(r2, dds::PeerTopic("r1", "r2", "relative")),
               dds::DdsError);
}

// The DdsError a participant with `identity`'s files in dir throws ("" if none).
std::string SecurityError(const std::string& dir, const std::string& identity) {
  try {
    dds::Participant participant({kBadFilesDomain, "bad_files", false, dir, identity});
  } catch (const dds::DdsError& e) {
    return e.what();
  }
  return {};
}

// Runs openssl with args in dir; true if it succeeded.
bool Openssl(const std::string& dir, const std::string& args) {
  return std::system(("cd '" + dir + "' && openssl " + args + " >/dev/null 2>&1").c_str()) == 0;
}

TEST(SecurityTest, BadSecurityFilesAreOneLineErrors) {
  SKIP_WITHOUT_OPENSSL();
  unsetenv("MRSLAM_DOMAIN");
  const testing::TempDir temp_dir("mrslam-bad-security");
  const std::string dir = temp_dir.path() + "/security";
  ASSERT_TRUE(MakeIdentities(dir, kProcesses));
  EXPECT_EQ(SecurityError(dir, "r1"), "");
  EXPECT_THAT(SecurityError(dir, "r3"), HasSubstr("r3_cert.pem: missing"));
  // r1's certificate and key in r3's place: a subject that is not r3.
  fs::copy_file(dir + "/r1_cert.pem", dir + "/r3_cert.pem");
  EXPECT_THAT(SecurityError(dir, "r3"), HasSubstr("subject CN 'r1' does not match the process identity 'r3'"));
  // An expired certificate of r2, signed by the right CA.
  ASSERT_TRUE(Openssl(dir, "req -new -key r2_key.pem -subj /C=ES/O=MRSLAM/CN=r2 -out r2.csr"));
  ASSERT_TRUE(Openssl(dir,
                      "x509 -req -in r2.csr -CA identity_ca.pem -CAkey identity_ca_key.pem -CAcreateserial "
                      "-days -1 -out r2_cert.pem"));
  EXPECT_THAT(SecurityError(dir, "r2"), HasSubstr("r2_cert.pem: certificate expired on"));
  // A process given such a folder says so in one line and exits 1.
  const std::string log = temp_dir.path() + "/agent.log";
  ChildProcess agent({BinPath("robot_agent"), "--scenario", SourcePath("config/paper_two_robots.yaml"), "--robot", "r2",
                      "--domain", std::to_string(kBadFilesDomain), "--security", dir},
                     log);
  testing::ExpectOneLineError(agent, log, "certificate expired on");
}

}  // namespace
}  // namespace mrslam
