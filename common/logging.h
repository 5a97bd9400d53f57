#pragma once

#include <string>

namespace mrslam::common {

// Sets up the process-wide spdlog logger: "[time] [name] [level] message" on stderr.
// level: trace, debug, info, warn, error (MRSLAM_LOG_LEVEL overrides it).
void SetupLogging(const std::string& process_name, const std::string& level = "info");

}  // namespace mrslam::common
