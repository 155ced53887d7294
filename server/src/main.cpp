// mdemd: the mdem job daemon. Settings from --config/flags (config.h), logs to stderr (logfmt
// lines: time, level, then key=value pairs), SIGTERM/SIGINT drain and exit 0.
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>

#include "daemon.h"

#ifndef MDEM_VERSION
#define MDEM_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  using namespace mdem::server;
  std::vector<std::string> args(argv + 1, argv + argc);
  for (const std::string& a : args) {
    if (a == "--help" || a == "-h") {
      std::cout << daemon_usage();
      return 0;
    }
    if (a == "--version") {
      std::cout << "mdemd " MDEM_VERSION "\n";
      return 0;
    }
  }
  DaemonConfig config;
  try {
    config = parse_daemon_config(args);
  } catch (const ConfigError& e) {
    std::cerr << "mdemd: " << e.what() << "\nRun 'mdemd --help' for the settings.\n";
    return 2;
  }
  auto logger = spdlog::stderr_logger_mt("mdemd");
  logger->set_pattern("time=%Y-%m-%dT%H:%M:%S.%eZ level=%l %v", spdlog::pattern_time_type::utc);
  logger->set_level(spdlog::level::from_str(config.log_level));
  logger->flush_on(spdlog::level::info);
  spdlog::set_default_logger(logger);

  // Signals are taken by sigwait below, not by whichever thread they hit.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  try {
    Daemon daemon(config);
    int sig = 0;
    sigwait(&stop_signals, &sig);
    spdlog::info("event=signal signal={}", sig == SIGTERM ? "SIGTERM" : "SIGINT");
    daemon.shutdown();
  } catch (const TokenFileError& e) {
    spdlog::error("event=startup_failed error=\"{}\"", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("event=startup_failed error=\"{}\"", e.what());
    return 1;
  }
  return 0;
}
