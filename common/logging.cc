#include "common/logging.h"

#include <cstdlib>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

namespace mrslam::common {

void SetupLogging(const std::string& process_name, const std::string& level) {
  auto logger = spdlog::stderr_color_mt(process_name);
  logger->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  const char* env = std::getenv("MRSLAM_LOG_LEVEL");
  logger->set_level(spdlog::level::from_str(env != nullptr ? env : level));
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);
}

}  // namespace mrslam::common
