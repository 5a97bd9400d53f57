#include "common/seed_range.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace mrslam::common {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST(SeedRangeTest, ARangeAndASingleSeed) {
  EXPECT_THAT(ParseSeedRange("--seeds", "3..6").Seeds(), ElementsAre(3, 4, 5, 6));
  EXPECT_THAT(ParseSeedRange("--seeds", " 7 ").Seeds(), ElementsAre(7));
  EXPECT_EQ(ParseSeedRange("--seeds", "0..9").size(), 10);
}

// The error names the flag and what is wrong.
std::string ErrorOf(const std::string& text) {
  try {
    ParseSeedRange("--seeds", text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

TEST(SeedRangeTest, BadRangesAreRejectedNamingTheFlag) {
  EXPECT_THAT(ErrorOf("5..2"), HasSubstr("the last seed is below the first"));
  EXPECT_THAT(ErrorOf("1..20000"), HasSubstr("more than 10000 seeds"));
  for (const char* bad : {"", "a..b", "-1..3", "1...3", "1..", "1.5"}) {
    EXPECT_THAT(ErrorOf(bad), HasSubstr("--seeds '")) << bad;
  }
}

}  // namespace
}  // namespace mrslam::common
