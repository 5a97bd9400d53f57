#include "common/dds/process_exit.h"

#include <cstdio>
#include <cstdlib>
#include <iostream>

#include <spdlog/spdlog.h>
#include <fastdds/dds/log/Log.hpp>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define MRSLAM_EXIT_WITH_DESTRUCTORS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define MRSLAM_EXIT_WITH_DESTRUCTORS 1
#endif
#endif

namespace mrslam::dds {

void ExitProcess(int code) {
  spdlog::shutdown();
  eprosima::fastdds::dds::Log::Flush();
  std::cout.flush();
  std::fflush(nullptr);
#ifdef MRSLAM_EXIT_WITH_DESTRUCTORS
  std::exit(code);
#else
  std::_Exit(code);
#endif
}

}  // namespace mrslam::dds
