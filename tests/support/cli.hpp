#pragma once
// Runs the freeflex program built beside the tests and captures its output and exit code.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace freeflex_test {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together (unless redirected otherwise)
};

/// `redirect`: what the shell does with the streams (default: stderr into stdout; both
/// are captured).
inline CliResult run_cli(const std::string& args, const std::string& redirect = "2>&1") {
  const std::string cmd = std::string("'") + FREEFLEX_CLI + "' " + args + " " + redirect;
  CliResult r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) r.output += buf;
  const int st = ::pclose(p);
  r.exit_code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

/// The paths handed out below, removed when the test program ends (set
/// FREEFLEX_KEEP_TEST_FILES to keep them for a look after a failure).
inline std::vector<std::string>& temp_paths() {
  static std::vector<std::string> paths;
  static const bool cleanup = [] {
    return std::atexit([] {
             if (std::getenv("FREEFLEX_KEEP_TEST_FILES")) return;
             for (const std::string& p : temp_paths()) {
               std::error_code ignored;  // a test may have removed it already
               std::filesystem::remove_all(p, ignored);
             }
           }) == 0;
  }();
  (void)cleanup;
  return paths;
}

/// A fresh temporary directory path (not created).
inline std::string temp_path(const std::string& stem) {
  static int counter = 0;
  const std::string path =
      "/tmp/freeflex_test_" + stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  temp_paths().push_back(path);
  return path;
}

inline std::string write_temp(const std::string& stem, const std::string& text) {
  const std::string path = temp_path(stem) + ".toml";
  temp_paths().push_back(path);
  std::ofstream(path) << text;
  return path;
}

inline bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

}  // namespace freeflex_test
