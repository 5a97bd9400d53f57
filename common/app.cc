#include "common/app.h"

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <limits>

#include <spdlog/spdlog.h>

namespace mrslam::common {

namespace {
std::atomic<bool> g_stop{false};
extern "C" void OnStopSignal(int /*signal*/) { g_stop = true; }
}  // namespace

void AddCommonFlags(CLI::App& app, CommonFlags* flags) {
  app.add_option("--scenario", flags->scenario, "Scenario YAML file")->required()->check(CLI::ExistingFile);
  app.add_option("--domain", flags->domain, "DDS domain id (0..232); MRSLAM_DOMAIN overrides it")
      ->check(CLI::Range(0, 232));
  app.add_option("--seed", flags->seed, "Run seed (overrides the scenario's 'seed')")
      ->check(CLI::Range(0LL, std::numeric_limits<long long>::max()));
  app.add_option("--set", flags->overrides, "Override a scenario key: key.path=value (repeatable)");
  app.add_flag("--shm", flags->shared_memory, "Use the shared-memory transport besides UDPv4");
  app.add_option("--log-level", flags->log_level, "trace, debug, info, warn, error, critical or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  app.add_option("--security", flags->security_dir,
                 "DDS-Security on, with the identities in this folder (scripts/security/make_identities.sh)")
      ->check(CLI::ExistingDirectory);
}

CLI::Validator FiniteNonNegative() {
  return CLI::Validator(
      [](const std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || v < 0.0) {
          return "'" + text + "' is not a finite number >= 0";
        }
        return {};
      },
      "FINITE >= 0");
}

const std::atomic<bool>& InstallStopHandler() {
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  return g_stop;
}

namespace {

int ParseAndRun(const std::string& name, CLI::App& app, int argc, char** argv,
                const std::function<int(const CLI::App&)>& body) {
  if (const auto status = ParseCommandLine(name, app, argc, argv)) return *status;
  return body(app);
}

}  // namespace

std::optional<int> ParseCommandLine(const std::string& name, CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << name << ": error: " << e.what() << " (see --help)\n";
    return 2;
  }
  return std::nullopt;
}

int RunMain(const std::string& name, const std::string& description, int argc, char** argv,
            const std::function<void(CLI::App&)>& add_flags, const std::function<int(const CLI::App&)>& body) {
  try {
    CLI::App app{description};
    add_flags(app);
    return ParseAndRun(name, app, argc, argv, body);
  } catch (const std::exception& e) {
    spdlog::shutdown();
    std::cerr << name << ": error: " << e.what() << "\n";
    return 1;
  } catch (...) {
    std::cerr << name << ": error: unknown exception\n";
    return 1;
  }
}

}  // namespace mrslam::common
