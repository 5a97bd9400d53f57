#include "tests/integration/child_process.h"

#include <fstream>
#include <sstream>

namespace mrslam::testing {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string MakeTempDir(const std::string& prefix) {
  std::string templ = "/tmp/" + prefix + "-XXXXXX";
  char* dir = mkdtemp(templ.data());
  return dir != nullptr ? std::string(dir) : std::string();
}

}  // namespace mrslam::testing
