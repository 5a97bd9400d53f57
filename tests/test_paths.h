#pragma once

#include <cstdlib>
#include <string>

// Where tests find the source tree (config/, test data) and the executables under test: compiled
// in by mrslam_add_test (MRSLAM_TEST_SOURCE_DIR, MRSLAM_TEST_BIN_DIR); the environment variables
// MRSLAM_SOURCE_DIR and MRSLAM_BIN_DIR override them.
namespace mrslam::testing {

inline std::string SourcePath(const std::string& rel) {
  const char* dir = std::getenv("MRSLAM_SOURCE_DIR");
  return std::string(dir != nullptr ? dir : MRSLAM_TEST_SOURCE_DIR) + "/" + rel;
}

inline std::string BinPath(const std::string& name) {
  const char* dir = std::getenv("MRSLAM_BIN_DIR");
  return std::string(dir != nullptr ? dir : MRSLAM_TEST_BIN_DIR) + "/" + name;
}

}  // namespace mrslam::testing
