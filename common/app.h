#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

// What every mrslam executable shares on its command line (--scenario, --domain, --seed,
// --set, --shm, --log-level, --security), the stop flag that SIGINT/SIGTERM raise, and the top-level
// error handling: one line on stderr and a non-zero exit code.
namespace mrslam::common {

struct CommonFlags {
  std::string scenario;
  int domain = -1;      // -1: the scenario's run.domain (MRSLAM_DOMAIN overrides both)
  long long seed = -1;  // -1: the scenario's seed
  std::vector<std::string> overrides;
  bool shared_memory = false;
  std::string log_level = "info";
  std::string security_dir;  // DDS-Security on with this folder's identities (empty: off)
};

void AddCommonFlags(CLI::App& app, CommonFlags* flags);

// Parses the command line: std::nullopt when it is good; else the exit code, after the help
// (--help) or one line "<name>: error: <what> (see --help)" on stderr.
std::optional<int> ParseCommandLine(const std::string& name, CLI::App& app, int argc, char** argv);

// A flag's value that must be a finite number >= 0 (CLI11's NonNegativeNumber lets NaN through).
CLI::Validator FiniteNonNegative();

// The flag SIGINT and SIGTERM set (installed once).
const std::atomic<bool>& InstallStopHandler();

// The whole of an executable's main: builds its command line (description, then add_flags adds
// its flags), parses it and runs body. Nothing escapes: exceptions become "<name>: error: <what>"
// on stderr and exit code 1; --help prints usage and exits 0; bad flags exit 2.
int RunMain(const std::string& name, const std::string& description, int argc, char** argv,
            const std::function<void(CLI::App&)>& add_flags, const std::function<int(const CLI::App&)>& body);

}  // namespace mrslam::common
