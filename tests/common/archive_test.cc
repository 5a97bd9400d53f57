// The Archive writes and reads back values, containers and matrices alike, and refuses what it
// cannot hold (a cut stream, a count larger than the bytes left); a snapshot file round-trips
// and one that is cut, altered or of another run is refused in one line.
#include "common/archive.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/rng.h"
#include "common/snapshot_file.h"

namespace mrslam::common {
namespace {

struct Sample {
  int a = 0;
  std::string name;
  std::vector<double> values;
  std::map<std::string, std::vector<std::uint32_t>> by_name;
  std::set<int> keys;
  std::optional<Eigen::Matrix3d> covariance;
  Eigen::MatrixXd dynamic;

  void Io(Archive& ar) { ar(a, name, values, by_name, keys, covariance, dynamic); }
};

Sample Filled() {
  Sample s;
  s.a = -7;
  s.name = "r12";
  s.values = {1.5, -0.0, 1e300};
  s.by_name = {{"r1", {1, 2, 3}}, {"r2", {}}};
  s.keys = {3, 1, 2};
  s.covariance = Eigen::Matrix3d::Random();
  s.dynamic = Eigen::MatrixXd::Random(2, 5);
  return s;
}

std::string Write(Sample s) {
  Archive ar = Archive::ForWriting();
  ar(s);
  return ar.bytes();
}

TEST(Archive, WritesAndReadsBackAlike) {
  const Sample in = Filled();
  Archive ar = Archive::ForReading(Write(in));
  Sample out;
  out.covariance.reset();
  ar(out);
  EXPECT_TRUE(ar.AtEnd());
  EXPECT_EQ(out.a, in.a);
  EXPECT_EQ(out.name, in.name);
  EXPECT_EQ(out.values, in.values);
  EXPECT_EQ(out.by_name, in.by_name);
  EXPECT_EQ(out.keys, in.keys);
  ASSERT_TRUE(out.covariance.has_value());
  EXPECT_EQ(*out.covariance, *in.covariance);
  EXPECT_EQ(out.dynamic, in.dynamic);
}

TEST(Archive, ARandomStreamGoesOnWhereItWas) {
  Rng a(42, "stream");
  a.Normal();  // the normal distribution now holds a spare value
  Archive w = Archive::ForWriting();
  a.Io(w);
  Rng b(1);
  Archive r = Archive::ForReading(w.bytes());
  b.Io(r);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(a.Normal(), b.Normal());
  EXPECT_EQ(a.Uniform(), b.Uniform());
}

TEST(Archive, ACutStreamIsAnError) {
  const std::string bytes = Write(Filled());
  for (std::size_t keep = 0; keep < bytes.size(); keep += 7) {
    Archive ar = Archive::ForReading(bytes.substr(0, keep));
    Sample out;
    EXPECT_THROW(ar(out), ArchiveError) << keep;
  }
}

TEST(Archive, AHugeCountIsRefusedBeforeAnyAllocation) {
  Archive w = Archive::ForWriting();
  std::uint64_t count = 1ULL << 60;
  w(count);
  Archive r = Archive::ForReading(w.bytes());
  std::vector<double> values;
  EXPECT_THROW(r(values), ArchiveError);
  EXPECT_TRUE(values.empty());
}

class SnapshotFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("mrslam-snapshot-test-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "r1.snapshot").string();
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string ReadAll() const {
    std::ifstream in(path_, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  void WriteAll(const std::string& bytes) const { std::ofstream(path_, std::ios::binary) << bytes; }

  std::filesystem::path dir_;
  std::string path_;
};

TEST_F(SnapshotFileTest, RoundTripsAndReplacesTheOldOne) {
  EXPECT_FALSE(ReadSnapshot(path_, "run A").has_value());
  WriteSnapshot(path_, "run A", {10, "state of step 10"});
  WriteSnapshot(path_, "run A", {20, "state of step 20"});
  const auto s = ReadSnapshot(path_, "run A");
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->step, 20U);
  EXPECT_EQ(s->payload, "state of step 20");
  EXPECT_FALSE(std::filesystem::exists(path_ + ".new"));
}

TEST_F(SnapshotFileTest, AnotherRunsSnapshotIsRefused) {
  WriteSnapshot(path_, "run A", {10, "x"});
  try {
    ReadSnapshot(path_, "run B");
    FAIL() << "read another run's snapshot";
  } catch (const SnapshotError& e) {
    EXPECT_NE(std::string(e.what()).find("of another run"), std::string::npos) << e.what();
  }
}

TEST_F(SnapshotFileTest, ACutOrAlteredFileIsRefused) {
  WriteSnapshot(path_, "run A", {10, "some state"});
  const std::string bytes = ReadAll();
  for (const std::size_t keep : {std::size_t{0}, std::size_t{5}, bytes.size() - 1}) {
    WriteAll(bytes.substr(0, keep));
    EXPECT_THROW(ReadSnapshot(path_, "run A"), SnapshotError) << keep;
  }
  std::string altered = bytes;
  altered[altered.size() / 2] ^= 0x01;
  WriteAll(altered);
  EXPECT_THROW(ReadSnapshot(path_, "run A"), SnapshotError);
}

}  // namespace
}  // namespace mrslam::common
